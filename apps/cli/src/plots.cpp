#include "tunekit/cli/plots.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>

#include <fmt/format.h>
#include <plplot/plstream.h>

#include "tunekit/fitting/error.hpp"

namespace tunekit::cli {
namespace {

// PLplot keeps global state behind its streams; one figure at a time.
std::mutex& plplot_mutex() {
  static std::mutex m;
  return m;
}

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
void set_palette(plstream& pls) {
  pls.scol0(0, 255, 255, 255);
  pls.scol0(1, 31, 119, 180);
  pls.scol0(2, 214, 39, 40);
  pls.scol0(3, 44, 160, 44);
  pls.scol0(4, 255, 127, 14);
  pls.scol0(5, 148, 103, 189);
  pls.scol0(6, 140, 86, 75);
  pls.scol0(7, 227, 119, 194);
  pls.scol0(8, 127, 127, 127);
  pls.scol0(15, 40, 40, 40);
}

}  // namespace

void render_png(const Figure& fig, const std::string& path) {
  if (fig.panels.empty()) throw InputError("a figure without panels", path);
  std::lock_guard lock(plplot_mutex());
  const auto dir = std::filesystem::path(path).parent_path();
  if (!dir.empty()) std::filesystem::create_directories(dir);
  {
    auto pls = std::make_unique<plstream>();
    pls->sdev("pngcairo");
    pls->sfnam(path.c_str());
    pls->spage(90, 90, fig.width_px, fig.height_px, 0, 0);
    set_palette(*pls);
    pls->init();
    pls->adv(0);
    pls->schr(0, 0.8);

    double total = 0;
    for (const auto& p : fig.panels) total += p.height_weight;
    const double top_margin = fig.title.empty() ? 0.04 : 0.09, bottom = 0.03;
    double y_top = 1.0 - top_margin;
    const double usable = 1.0 - top_margin - bottom;
    for (std::size_t i = 0; i < fig.panels.size(); ++i) {
      const Panel& p = fig.panels[i];
      const double h = usable * p.height_weight / total;
      const double y0 = y_top - h + 0.075, y1 = y_top - 0.02;
      y_top -= h;
      pls->vpor(0.09, 0.97, y0, y1);

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
      if (!p.log_x) rx.pad(0.0);
      if (rx.hi == rx.lo) rx.pad(0.05);
      ry.pad(0.06);
      pls->wind(rx.lo, rx.hi, ry.lo, ry.hi);
      pls->col0(15);
      pls->width(1);
      pls->lsty(1);
      const std::string xopt = std::string("bcnstg") + (p.log_x ? "l" : "");
      const std::string yopt = std::string("bcnstvg") + (p.log_y ? "l" : "");
      pls->box(xopt.c_str(), 0, 0, yopt.c_str(), 0, 0);
      pls->lab(p.xlabel.c_str(), p.ylabel.c_str(), p.title.c_str());

      std::vector<std::string> labels;
      std::vector<PLINT> opts, colors, styles, sym_colors, sym_numbers;
      std::vector<PLFLT> widths, sym_scales;
      for (const auto& s : p.series) {
        std::vector<PLFLT> xs, ys;
        for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
          const double ax = axis_value(s.x[k], p.log_x), ay = axis_value(s.y[k], p.log_y);
          if (std::isfinite(ax) && std::isfinite(ay)) {
            xs.push_back(ax);
            ys.push_back(ay);
          }
        }
        if (xs.empty()) continue;
        pls->col0(s.color);
        if (s.style == Series::Style::points) {
          pls->poin(static_cast<PLINT>(xs.size()), xs.data(), ys.data(), 17);
        } else {
          pls->lsty(s.style == Series::Style::dashed ? 2 : 1);
          pls->width(1.6);
          pls->line(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
          pls->lsty(1);
          pls->width(1);
        }
        if (!s.label.empty()) {
          labels.push_back(s.label);
          opts.push_back(s.style == Series::Style::points ? PL_LEGEND_SYMBOL : PL_LEGEND_LINE);
          colors.push_back(s.color);
          styles.push_back(s.style == Series::Style::dashed ? 2 : 1);
          widths.push_back(1.6);
          sym_colors.push_back(s.color);
          sym_numbers.push_back(3);
          sym_scales.push_back(1.0);
        }
      }
      if (!labels.empty()) {
        std::vector<const char*> text, symbols;
        for (const auto& l : labels) {
          text.push_back(l.c_str());
          symbols.push_back("#(728)");
        }
        PLFLT lw, lh;
        pls->col0(15);
        pls->legend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, PL_POSITION_RIGHT | PL_POSITION_TOP | PL_POSITION_INSIDE,
                    0.01, 0.01, 0.08, 0, 15, 1, 0, 0, static_cast<PLINT>(labels.size()), opts.data(), 1.0, 0.9, 1.6, 1.0,
                    colors.data(), text.data(), nullptr, nullptr, nullptr, nullptr, colors.data(), styles.data(),
                    widths.data(), sym_colors.data(), sym_scales.data(), sym_numbers.data(), symbols.data());
      }
    }
    if (!fig.title.empty()) {
      pls->vpor(0, 1, 0, 1);
      pls->wind(0, 1, 0, 1);
      pls->col0(15);
      pls->schr(0, 1.0);
      pls->mtex("t", -1.6, 0.5, 0.5, fig.title.c_str());
    }
  }  // ~plstream ends the stream and closes the file
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || std::filesystem::file_size(path, ec) == 0)
    throw InputError("the plot could not be written", path);
}

}  // namespace tunekit::cli
