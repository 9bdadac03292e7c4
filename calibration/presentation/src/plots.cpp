#include "tunekit/calibration/presentation/plots.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <functional>
#include <iostream>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

#include <fmt/format.h>
#include <plplot/plplot.h>

#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/shared_library.hpp"

namespace tunekit::calibration {
namespace {

// PLplot keeps global state behind its streams; one figure at a time.
std::mutex& plplot_mutex() {
  static std::mutex m;
  return m;
}

// PLplot's C functions used here. PLplot (and the libraries it needs: freetype, qhull, libltdl,
// ...) is opened when the first figure is drawn, so that no other command loads it at start-up.
struct PlplotApi {
  decltype(&c_plmkstrm) mkstrm;
  decltype(&c_plsstrm) sstrm;
  decltype(&c_plend1) end1;
  decltype(&c_plend) end;
  decltype(&c_plsdev) sdev;
  decltype(&c_plsfnam) sfnam;
  decltype(&c_plspage) spage;
  decltype(&c_plscol0) scol0;
  decltype(&c_plinit) init;
  decltype(&c_pladv) adv;
  decltype(&c_plschr) schr;
  decltype(&c_plvpor) vpor;
  decltype(&c_plwind) wind;
  decltype(&c_plcol0) col0;
  decltype(&c_plwidth) width;
  decltype(&c_pllsty) lsty;
  decltype(&c_plbox) box;
  decltype(&c_plmtex) mtex;
  decltype(&c_pllab) lab;
  decltype(&c_plpoin) poin;
  decltype(&c_plline) line;
  decltype(&c_plgchr) gchr;
  decltype(&c_plgspa) gspa;
  decltype(&c_plfill) fill;
  decltype(&c_plptex) ptex;
};

const PlplotApi& plplot_api() {
  static const PlplotApi api = [] {
    static core::SharedLibrary lib(TUNEKIT_PLPLOT_SONAME, "figures (PNG and SVG plots)", "libplplot17");
    PlplotApi a;
    a.mkstrm = lib.function<decltype(&c_plmkstrm)>("c_plmkstrm");
    a.sstrm = lib.function<decltype(&c_plsstrm)>("c_plsstrm");
    a.end1 = lib.function<decltype(&c_plend1)>("c_plend1");
    a.end = lib.function<decltype(&c_plend)>("c_plend");
    a.sdev = lib.function<decltype(&c_plsdev)>("c_plsdev");
    a.sfnam = lib.function<decltype(&c_plsfnam)>("c_plsfnam");
    a.spage = lib.function<decltype(&c_plspage)>("c_plspage");
    a.scol0 = lib.function<decltype(&c_plscol0)>("c_plscol0");
    a.init = lib.function<decltype(&c_plinit)>("c_plinit");
    a.adv = lib.function<decltype(&c_pladv)>("c_pladv");
    a.schr = lib.function<decltype(&c_plschr)>("c_plschr");
    a.vpor = lib.function<decltype(&c_plvpor)>("c_plvpor");
    a.wind = lib.function<decltype(&c_plwind)>("c_plwind");
    a.col0 = lib.function<decltype(&c_plcol0)>("c_plcol0");
    a.width = lib.function<decltype(&c_plwidth)>("c_plwidth");
    a.lsty = lib.function<decltype(&c_pllsty)>("c_pllsty");
    a.box = lib.function<decltype(&c_plbox)>("c_plbox");
    a.mtex = lib.function<decltype(&c_plmtex)>("c_plmtex");
    a.lab = lib.function<decltype(&c_pllab)>("c_pllab");
    a.poin = lib.function<decltype(&c_plpoin)>("c_plpoin");
    a.line = lib.function<decltype(&c_plline)>("c_plline");
    a.gchr = lib.function<decltype(&c_plgchr)>("c_plgchr");
    a.gspa = lib.function<decltype(&c_plgspa)>("c_plgspa");
    a.fill = lib.function<decltype(&c_plfill)>("c_plfill");
    a.ptex = lib.function<decltype(&c_plptex)>("c_plptex");
    return a;
  }();
  return api;
}

// One PLplot stream, as PLplot's own C++ binding (plstream) drives it: made current on creation,
// ended on destruction (with the library's global state, as the binding does for its last stream).
class PlStream {
 public:
  PlStream() : api_(plplot_api()) {
    api_.mkstrm(&stream_);
    api_.sstrm(stream_);
  }
  ~PlStream() {
    api_.sstrm(stream_);
    api_.end1();
    api_.end();
  }
  PlStream(const PlStream&) = delete;
  PlStream& operator=(const PlStream&) = delete;
  const PlplotApi* operator->() const { return &api_; }

 private:
  const PlplotApi& api_;
  PLINT stream_ = 0;
};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool valid() const { return lo <= hi; }
  void pad(double frac) {
    if (hi == lo) {
      const double d = lo == 0 ? 1.0 : std::abs(lo) * 0.1;
      lo -= d;
      hi += d;
      return;
    }
    const double d = (hi - lo) * frac;
    lo -= d;
    hi += d;
  }
};

double axis_value(double v, bool log) {
  if (!log) return v;
  return v > 0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
}

// Palette: index 0 background (white), 1..8 line colours, 15 axes (dark grey).
void set_palette(PlStream& pls) {
  pls->scol0(0, 255, 255, 255);
  pls->scol0(1, 31, 119, 180);
  pls->scol0(2, 214, 39, 40);
  pls->scol0(3, 44, 160, 44);
  pls->scol0(4, 255, 127, 14);
  pls->scol0(5, 148, 103, 189);
  pls->scol0(6, 140, 86, 75);
  pls->scol0(7, 227, 119, 194);
  pls->scol0(8, 127, 127, 127);
  pls->scol0(15, 40, 40, 40);
}

std::string plot_tick_text(double v) {
  if (v >= 1e-3 && v < 1e5) return fmt::format("{:g}", v);
  const int k = static_cast<int>(std::floor(std::log10(v) + 1e-9));
  const double m = v / std::pow(10.0, k);
  return std::abs(m - 1) < 1e-6 ? fmt::format("10#u{}#d", k) : fmt::format("{:g}#(727)10#u{}#d", std::round(m), k);
}

// Labels a logarithmic axis at its decades and (for short spans) at 2x and 5x: PLplot's own
// log labels name the decades only, which leaves a one-decade axis with a single number.
void label_log_axis(PlStream& pls, bool x_axis, double lo_exp, double hi_exp) {
  for (double v : log_axis_ticks(lo_exp, hi_exp)) {
    const double frac = (std::log10(v) - lo_exp) / (hi_exp - lo_exp);
    const std::string text = plot_tick_text(v);
    if (x_axis) pls->mtex("b", 1.4, frac, 0.5, text.c_str());
    else pls->mtex("lv", 0.6, frac, 1.0, text.c_str());
  }
}

// Device of a file name: svgcairo for .svg, pngcairo for .png.
const char* plot_device(const std::string& path) {
  const auto ext = std::filesystem::path(path).extension().string();
  if (ext == ".svg") return "svgcairo";
  if (ext == ".png") return "pngcairo";
  throw InputError("a plot file must end in .svg or .png", path);
}

// Draws the legend of a panel in the band [x0, x1] of the page (normalised page coordinates) with
// its top at y_top: a white box with a frame, one row per series (its sample and its label,
// left-aligned). Drawn here rather than by PLplot's legend, whose outside-corner placement put a
// legend over the panel above and whose estimate of the labels' width ran it off the page.
void draw_legend(PlStream& pls, const std::vector<const Series*>& entries, double x0, double x1, double y_top,
                 int width_pt) {
  PLFLT def_mm = 0, ht_mm = 0, xmin_mm = 0, xmax_mm = 0, ymin_mm = 0, ymax_mm = 0;
  pls->schr(0, 0.72);
  pls->gchr(&def_mm, &ht_mm);
  pls->gspa(&xmin_mm, &xmax_mm, &ymin_mm, &ymax_mm);
  const double n = static_cast<double>(entries.size()), rows = n + 0.6;
  const double row = 1.8 * ht_mm / (ymax_mm - ymin_mm);  // one row, normalised page height
  pls->vpor(x0, x1, std::max(0.0, y_top - row * rows), y_top);
  pls->wind(0, 1, 0, rows);
  PLFLT bx[4] = {0, 1, 1, 0}, by[4] = {0, 0, rows, rows};
  pls->col0(0);
  pls->fill(4, bx, by);
  pls->col0(15);
  pls->width(1);
  pls->lsty(1);
  pls->box("bc", 0, 0, "bc", 0, 0);
  const double pt = 1.0 / ((x1 - x0) * width_pt);  // one point in the box's x units
  const double margin = 6 * pt, sample = 26 * pt;
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const Series& s = *entries[k];
    PLFLT yc = rows - 0.3 - (static_cast<double>(k) + 0.5);
    pls->col0(s.color);
    if (s.style == Series::Style::points) {
      PLFLT xc = margin + sample / 2;
      pls->poin(1, &xc, &yc, 17);
    } else {
      PLFLT xs[2] = {margin, margin + sample}, ys[2] = {yc, yc};
      pls->lsty(s.style == Series::Style::dashed ? 2 : 1);
      pls->width(1.6);
      pls->line(2, xs, ys);
      pls->lsty(1);
      pls->width(1);
    }
    pls->ptex(2 * margin + sample, yc, 1, 0, 0.0, s.label.c_str());
  }
  pls->schr(0, 0.8);
}

}  // namespace

std::vector<double> log_axis_ticks(double lo_exp, double hi_exp) {
  std::vector<double> v;
  if (!std::isfinite(lo_exp) || !std::isfinite(hi_exp) || hi_exp < lo_exp) return v;
  const bool minors = hi_exp - lo_exp <= 3.0;
  for (int k = static_cast<int>(std::floor(lo_exp)) - 1; k <= static_cast<int>(std::ceil(hi_exp)); ++k)
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !minors) continue;
      const double e = k + std::log10(m);
      if (e >= lo_exp - 1e-9 && e <= hi_exp + 1e-9) v.push_back(std::pow(10.0, e));
    }
  return v;
}

void render_png(const Figure& fig, const std::string& path) {
  if (std::filesystem::path(path).extension() != ".png") throw InputError("render_png writes .png files", path);
  render_figure(fig, path);
}

void render_svg(const Figure& fig, const std::string& path) {
  if (std::filesystem::path(path).extension() != ".svg") throw InputError("render_svg writes .svg files", path);
  render_figure(fig, path);
}

namespace {

// With share_x: the x range of every panel's data.
Range shared_x_range(const Figure& fig) {
  Range shared_x;
  if (fig.share_x)
    for (const auto& p : fig.panels)
      for (const auto& s : p.series)
        for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k)
          if (std::isfinite(axis_value(s.y[k], p.log_y))) shared_x.add(axis_value(s.x[k], p.log_x));
  return shared_x;
}

// One series of panel p, a line in pieces between missing values or points. False when it has
// no finite point (nothing drawn).
bool draw_series(PlStream& pls, const Series& s, const Panel& p) {
  // A line is drawn in pieces between missing (non-finite) values: a gap stays a gap.
  std::vector<std::vector<PLFLT>> xs(1), ys(1);
  bool any = false;
  for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
    const double ax = axis_value(s.x[k], p.log_x), ay = axis_value(s.y[k], p.log_y);
    if (std::isfinite(ax) && std::isfinite(ay)) {
      xs.back().push_back(ax);
      ys.back().push_back(ay);
      any = true;
    } else if (!xs.back().empty()) {
      xs.emplace_back();
      ys.emplace_back();
    }
  }
  if (!any) return false;
  pls->col0(s.color);
  for (std::size_t piece = 0; piece < xs.size(); ++piece) {
    const auto n = static_cast<PLINT>(xs[piece].size());
    if (n == 0) continue;
    if (s.style == Series::Style::points) {
      pls->poin(n, xs[piece].data(), ys[piece].data(), 17);
    } else {
      pls->lsty(s.style == Series::Style::dashed ? 2 : 1);
      pls->width(1.6);
      pls->line(n, xs[piece].data(), ys[piece].data());
      pls->lsty(1);
      pls->width(1);
    }
  }
  return true;
}

// Panel p in the viewport set for it: its data's range (x shared by every panel with
// share_x), the frame, the axes' labels and title, its series and their legend.
void draw_panel(PlStream& pls, const Figure& fig, const Panel& p, const Range& shared_x, double legend_room, double y1,
                const std::string& path) {
  Range rx, ry;
  for (const auto& s : p.series)
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      const double ax = axis_value(s.x[k], p.log_x), ay = axis_value(s.y[k], p.log_y);
      if (std::isfinite(ax) && std::isfinite(ay)) {
        rx.add(ax);
        ry.add(ay);
      }
    }
  if (!rx.valid() || !ry.valid()) throw InputError(fmt::format("panel '{}' has no finite data to plot", p.title), path);
  if (fig.share_x && shared_x.valid()) rx = shared_x;
  if (!p.log_x) rx.pad(0.0);
  if (rx.hi == rx.lo) rx.pad(0.05);
  ry.pad(0.06);
  pls->wind(rx.lo, rx.hi, ry.lo, ry.hi);
  pls->col0(15);
  pls->width(1);
  pls->lsty(1);
  // Log axes: ticks and grid from PLplot, numbers from label_log_axis.
  const std::string xopt = p.log_x ? "bcstgl" : "bcnstg";
  const std::string yopt = p.log_y ? "bcstvgl" : "bcnstvg";
  pls->box(xopt.c_str(), 0, 0, yopt.c_str(), 0, 0);
  if (p.log_x) label_log_axis(pls, true, rx.lo, rx.hi);
  if (p.log_y) label_log_axis(pls, false, ry.lo, ry.hi);
  // The panel's title left-aligned above its frame (centred, it read as the axis label of the
  // panel above).
  pls->lab(p.xlabel.c_str(), p.ylabel.c_str(), "");
  pls->mtex("t", 0.8, 0.0, 0.0, p.title.c_str());

  std::vector<const Series*> legend;
  for (const auto& s : p.series)
    if (draw_series(pls, s, p) && !s.label.empty()) legend.push_back(&s);
  // The legend sits right of the data, its top level with the panel's frame.
  if (!legend.empty()) draw_legend(pls, legend, 0.97 - legend_room + 0.01, 0.99, y1, fig.width_px);
}

}  // namespace

/// Draws the figure with PLplot into `path` (the device for its extension).
void draw_figure(const Figure& fig, const std::string& path, const char* device) {
  PlStream pls;
  pls->sdev(device);
  pls->sfnam(path.c_str());
  pls->spage(90, 90, fig.width_px, fig.height_px, 0, 0);
  set_palette(pls);
  pls->init();
  pls->adv(0);
  pls->schr(0, 0.8);

  double total = 0;
  for (const auto& p : fig.panels) total += p.height_weight;
  const Range shared_x = shared_x_range(fig);  // with share_x: the x range of every panel's data
  const double top_margin = fig.title.empty() ? 0.04 : 0.09, bottom = 0.03;
  double y_top = 1.0 - top_margin;
  const double usable = 1.0 - top_margin - bottom;
  for (std::size_t i = 0; i < fig.panels.size(); ++i) {
    const Panel& p = fig.panels[i];
    const double h = usable * p.height_weight / total;
    const double y0 = y_top - h + 0.075, y1 = y_top - 0.02;
    y_top -= h;
    // The legend sits right of the data, never over it: the plot area leaves it room.
    // With a shared x axis every panel leaves the same room, so that their x axes line up.
    std::size_t longest_label = 0;
    for (const auto& q : fig.panels)
      if (&q == &p || fig.share_x)
        for (const auto& s : q.series) longest_label = std::max(longest_label, s.label.size());
    const double legend_room = longest_label == 0 ? 0.0 : std::min(0.4, 0.05 + 0.0095 * longest_label);
    pls->vpor(0.09, 0.97 - legend_room, y0, y1);

    draw_panel(pls, fig, p, shared_x, legend_room, y1, path);
  }
  if (!fig.title.empty()) {
    pls->vpor(0, 1, 0, 1);
    pls->wind(0, 1, 0, 1);
    pls->col0(15);
    pls->schr(0, 1.0);
    pls->mtex("t", -1.6, 0.5, 0.5, fig.title.c_str());
  }
}  // ~PlStream ends the stream and closes the file

/// Runs `draw` in a child process: the plot library aborts its process on conditions tunekit
/// cannot catch (GLib's g_error when a memory cap keeps pango from starting a thread, SIGTRAP;
/// PLplot's exit on a file it cannot open). A child that does not end normally is one plain
/// InputError, and tunekit carries on without the figure. The child's messages go nowhere.
void draw_isolated(const std::function<void()>& draw, const std::string& path) {
  std::cout.flush();
  std::cerr.flush();
  const pid_t pid = ::fork();
  if (pid < 0) throw InputError("the figure was not drawn: cannot start the plot process (out of memory?)", path);
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
    }
    try {
      draw();
    } catch (...) {
      ::_exit(1);
    }
    ::_exit(0);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  throw InputError(WIFSIGNALED(status)
                       ? fmt::format("the figure was not drawn: the plot library died ({}; out of memory?)",
                                     ::strsignal(WTERMSIG(status)))
                       : std::string("the figure was not drawn: the plot library failed"),
                   path);
}

void render_figure(const Figure& fig, const std::string& path) {
  if (fig.panels.empty()) throw InputError("a figure without panels", path);
  const char* device = plot_device(path);
  std::lock_guard lock(plplot_mutex());
  const auto dir = std::filesystem::path(path).parent_path();
  std::error_code dir_ec;
  if (!dir.empty()) std::filesystem::create_directories(dir, dir_ec);
  // PLplot opens the file itself: a link out of the directory is refused first (atomic_file.hpp).
  core::require_link_within_directory(path);
  // PLplot aborts the whole process (its own message, exit 1) on a file it cannot open: try first.
  if (!std::ofstream(path, std::ios::binary | std::ios::app))
    throw InputError("cannot write the figure there (a missing or read-only directory)", path);
  draw_isolated([&] { draw_figure(fig, path, device); }, path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || std::filesystem::file_size(path, ec) == 0)
    throw InputError("the plot could not be written", path);
}

}  // namespace tunekit::calibration
