#include "calibrate_liquefier.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <filesystem>
#include <iostream>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/overlay.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/experiments.hpp"

#ifndef TUNEKIT_CAPTURE_EXE
#define TUNEKIT_CAPTURE_EXE "tunekit-capture"
#endif

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

// The ring test's settings (ring-print protocol): a stronger modulation than its default so the
// attenuated width swing stays well above the measurement noise.
constexpr double kRingAmplitude = 0.3;
constexpr double kRingPeriods = 6;
// Ring samples before this angle (rad) are left out: the liquefier is still filling after the
// travel move that precedes the ring.
constexpr double kRingSkipRad = 2.5;
// Share of each line's lead-in (low flow before the step) left out of the width record.
constexpr double kLeadSkip = 2.0 / 3.0;

// Image px (OpenCV: pixel centres at integers) -> bed mm.
struct BedMapping {
  bool known = false;  // the camera's placement on the bed is known (the simulated camera)
  double x0_mm = 0, y1_mm = 0, px_per_mm = 0;
  double x(double u) const { return x0_mm + (u + 0.5) / px_per_mm; }
  double y(double v) const { return y1_mm - (v + 0.5) / px_per_mm; }
};

double liq_median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Averages `frames` frames of a camera after `settle_s`, through the tunekit-capture helper
// (the only program linked with OpenCV's videoio, so that `tunekit` itself starts fast).
std::string capture_from_device(const LiquefierCameraArgs& a, const std::string& out_png) {
  std::string exe = TUNEKIT_CAPTURE_EXE;
  // Next to the running tunekit when installed side by side.
  std::error_code ec;
  const auto self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && fs::exists(self.parent_path() / "tunekit-capture"))
    exe = (self.parent_path() / "tunekit-capture").string();
  const std::string frames = std::to_string(a.frames), settle = fmt::format("{}", a.settle_s);
  const pid_t pid = ::fork();
  if (pid < 0) throw MachineError("cannot start the camera helper (fork failed)", a.camera_device);
  const std::string log = out_png + ".log";
  if (pid == 0) {
    // The helper's message goes to a log next to the photo; it is quoted in our one error line.
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) ::dup2(fd, STDERR_FILENO);
    ::execl(exe.c_str(), exe.c_str(), a.camera_device.c_str(), out_png.c_str(), frames.c_str(), settle.c_str(),
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 3;
  if (code == 127) throw MachineError(fmt::format("the camera helper '{}' could not be run", exe), a.camera_device);
  if (code != 0) {
    std::string why = ident::read_file_bytes(log);
    while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
    if (const auto nl = why.find_last_of('\n'); nl != std::string::npos) why = why.substr(nl + 1);
    if (const auto colon = why.rfind(": "); colon != std::string::npos) why = why.substr(colon + 2);
    throw MachineError(fmt::format("{}; check the device, its permissions (group video) and that no other program uses "
                                   "it (the printed tests are kept in the run directory)",
                                   why.empty() ? "the camera gave no picture" : why),
                       a.camera_device);
  }
  return out_png;
}

struct RingFit {
  double c = 0, s = 0;  // y ~ a0 + a1 t + c cos(w t) + s sin(w t)
};

RingFit fit_sine_at(const std::vector<double>& t, const std::vector<double>& y, double w) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(t.size()), 4);
  Eigen::VectorXd b(static_cast<Eigen::Index>(t.size()));
  for (std::size_t i = 0; i < t.size(); ++i) {
    const auto r = static_cast<Eigen::Index>(i);
    A(r, 0) = 1;
    A(r, 1) = t[i];
    A(r, 2) = std::cos(w * t[i]);
    A(r, 3) = std::sin(w * t[i]);
    b(r) = y[i];
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  return {x(2), x(3)};
}

}  // namespace

LiquefierPath choose_liquefier_path(const std::string& choice, const machine::MachineProfile& profile,
                                    const std::string& profile_path) {
  if (choice == "camera") return LiquefierPath::camera;
  if (choice == "load-cell") {
    if (!profile.sensors.load_cell)
      throw InputError(
          "--liquefier load-cell needs a load cell ([sensors] load_cell = true); without one use "
          "--liquefier camera",
          profile_path);
    return LiquefierPath::load_cell;
  }
  if (choice == "auto") return profile.sensors.load_cell ? LiquefierPath::load_cell : LiquefierPath::camera;
  throw InputError(fmt::format("--liquefier must be auto, load-cell or camera, not '{}'", choice));
}

void check_photo_source(const LiquefierCameraArgs& a, bool sim_machine, bool can_prompt) {
  const int sources = (a.camera.empty() ? 0 : 1) + (a.photo.empty() ? 0 : 1) + (a.camera_device.empty() ? 0 : 1);
  if (sources > 1) throw InputError("give one photo source: --camera sim, --photo FILE or --camera-device DEVICE");
  if (!a.camera.empty() && a.camera != "sim")
    throw InputError(
        fmt::format("--camera '{}': only 'sim' (the simulated printer's camera); a real camera is "
                    "--camera-device DEVICE",
                    a.camera));
  if (a.camera == "sim" && !sim_machine)
    throw InputError("--camera sim photographs the simulated printer: use it with --machine sim");
  if (a.camera.empty() && a.px_per_mm <= 0)
    throw InputError(
        "the camera path needs the photo's scale on the bed: --px-per-mm (e.g. from 'tunekit linewidth "
        "--chessboard ... --save-camera')");
  if (sources == 0 && !can_prompt)
    throw InputError(
        "the camera path needs a photo of the printed tests and this is not a terminal to ask for one: "
        "give --photo FILE, --camera-device DEVICE (or --camera sim with --machine sim)");
}

std::vector<CameraTest> camera_tests() {
  return {{"liquefier-lines", "line-steps", {}},
          {"liquefier-ring", "ring-print", {{"amplitude", kRingAmplitude}, {"periods", kRingPeriods}}}};
}

CameraAnalysis analyze_camera_prints(const std::string& run_dir, const LiquefierCameraArgs& a,
                                     const machine::MachineProfile& profile,
                                     std::map<std::string, protocols::RunResult>& runs,
                                     const std::shared_ptr<sim::SimPrintBed>& bed, bool can_prompt, CliContext& ctx) {
  const std::string dir = run_dir + "/liquefier-camera";
  fs::create_directories(dir);
  CameraAnalysis out;
  BedMapping map;
  map.px_per_mm = a.px_per_mm;

  // 1. The photo.
  cv::Mat photo;
  if (a.camera == "sim") {
    sim::SimCameraFrame frame;
    photo = bed->photograph(sim::SimCameraOptions{}, &frame);
    out.photo = dir + "/photo.png";
    vision::write_png(out.photo, photo);
    map = {true, frame.x0_mm, frame.y1_mm, frame.px_per_mm};
  } else {
    std::string path = a.photo;
    if (!a.camera_device.empty()) {
      path = capture_from_device(a, dir + "/photo.png");
    } else if (path.empty()) {
      if (!can_prompt) throw InputError("no photo of the printed tests (give --photo FILE)");
      ctx.err << "Photograph the printed line test and ring from above (bed X to the right) and give the file path: ";
      ctx.err.flush();
      if (!std::getline(std::cin, path) || path.empty()) throw InputError("no photo file was given");
      while (!path.empty() && (path.back() == ' ' || path.back() == '\r')) path.pop_back();
    }
    photo = vision::read_image(path, vision::ImageColor::gray);
    out.photo = path;
    if (path != dir + "/photo.png") {
      // The photo is kept with the run.
      out.photo = dir + "/photo" + fs::path(path).extension().string();
      fs::copy_file(path, out.photo, fs::copy_options::overwrite_existing);
    }
  }

  // 2. The lines and the ring in it.
  const cv::Mat gray = vision::to_gray_float(photo);
  vision::LineWidthOptions lo;
  lo.min_length_px = std::max(60.0, 20 * map.px_per_mm);
  const auto measured = vision::measure_line_widths(gray, lo);
  out.overlay = dir + "/overlay.png";
  if (measured.lines.empty()) {
    vision::write_overlay(out.overlay, vision::draw_overlay(photo, &measured, {}, "no printed line found"));
    throw InputError(
        "the photo shows no printed line (is the print in the frame, in focus and lit?); the printed runs "
        "are kept in " +
            run_dir,
        out.photo);
  }
  vision::write_overlay(out.overlay, vision::draw_overlay(photo, &measured, {}, ""));

  const auto& line_run = runs.at("liquefier-lines");
  const auto layout = protocols::line_steps_layout(line_run.experiment.params, profile);
  const double v_line = layout.front().path.front().speed_mm_s;
  std::vector<const vision::MeasuredLine*> straight;
  const vision::MeasuredLine* ring = nullptr;
  for (const auto& l : measured.lines) {
    if (l.closed || (l.bbox.width < 3 * l.bbox.height && l.bbox.height < 3 * l.bbox.width)) {
      if (ring == nullptr) ring = &l;
    } else if (l.bbox.width > 5 * l.bbox.height) {
      straight.push_back(&l);
    }
  }
  if (straight.empty())
    throw InputError(
        fmt::format("the photo shows {} printed feature(s) but none of the line test's straight lines along "
                    "X (photograph with the bed's X axis to the right)",
                    measured.lines.size()),
        out.photo);
  // Printed first = highest Y = topmost in the photo.
  std::sort(straight.begin(), straight.end(), [](const auto* p, const auto* q) { return p->bbox.y < q->bbox.y; });
  nlohmann::json warnings = nlohmann::json::array();
  for (const auto& w : measured.warnings) warnings.push_back(w);
  if (straight.size() != layout.size())
    warnings.push_back(fmt::format("the photo shows {} of the {} printed lines; the first {} are used in print order",
                                   straight.size(), layout.size(), std::min(straight.size(), layout.size())));

  // 3. Widths along the lines -> one time record (line k starts 1 s after line k-1 ends).
  std::vector<vision::TimedWidth> rows;
  nlohmann::json lines_json = nlohmann::json::array();
  double t_offset = 0;
  nlohmann::json plot_line;
  for (std::size_t k = 0; k < std::min(straight.size(), layout.size()); ++k) {
    const auto& ml = *straight[k];
    const auto& pl = layout[k];
    const double L = pl.length_mm();
    // Where the line lies on its path: from the camera's known placement, or else from the
    // line's far end (the nozzle stopped at the path's end; the bead ends half a width beyond).
    std::vector<double> end_widths;
    for (const auto& s : ml.samples)
      if (s.valid() && s.x_px > ml.bbox.x + ml.bbox.width - 5 * map.px_per_mm) end_widths.push_back(s.width_px);
    const double w_end_px = end_widths.empty() ? 0 : liq_median(end_widths);
    const double x_end_px = ml.bbox.x + ml.bbox.width - 0.5;
    std::vector<double> s_mm, w_mm, conf;
    for (const auto& s : ml.samples) {
      if (!s.valid()) continue;
      const double pos = map.known ? map.x(s.x_px) - pl.x0_mm : L - (x_end_px - s.x_px - w_end_px / 2) / map.px_per_mm;
      // The first two thirds of the lead-in are left out: there the nozzle is still filling
      // after the travel move (a start from empty, not the step under test); the rest is the
      // settled level before the step (and, in the joined record, after the previous line's).
      if (pos < kLeadSkip * pl.path.front().length_mm || pos > L) continue;
      s_mm.push_back(pos);
      w_mm.push_back(s.width_px / map.px_per_mm);
      conf.push_back(s.confidence);
    }
    if (s_mm.size() < 20) {
      warnings.push_back(fmt::format("line {}: too few measured samples on the path", k + 1));
      continue;
    }
    // map_path expects ascending profile positions from the path start: give it positions.
    std::vector<std::size_t> order(s_mm.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](auto i, auto j) { return s_mm[i] < s_mm[j]; });
    std::vector<double> ss, ww, cc;
    for (auto i : order) {
      ss.push_back(s_mm[i]);
      ww.push_back(w_mm[i]);
      cc.push_back(conf[i]);
    }
    vision::PathMapping how;
    how.offset_mm = ss.front();  // map_path counts along the profile from its first sample
    how.filament_diameter_mm = profile.extruder.filament_diameter_mm;
    how.layer_height_mm = line_run.experiment.params.at("z_mm");
    auto timed = vision::map_path(ss, ww, cc, pl.path, how);
    double mean_w = 0;
    for (auto& r : timed) {
      mean_w += r.width_mm;
      if (k == 0) {
        plot_line["s_mm"].push_back(r.s_mm);
        plot_line["width_mm"].push_back(r.width_mm);
        plot_line["setpoint_mm"].push_back(r.setpoint_mm);
      }
      r.t_s += t_offset;
      rows.push_back(r);
    }
    lines_json.push_back({{"line", k + 1},
                          {"y_mm", pl.y_mm},
                          {"samples", timed.size()},
                          {"mean_width_mm", timed.empty() ? 0 : mean_w / static_cast<double>(timed.size())},
                          {"placement", map.known ? "camera frame" : "line end"}});
    t_offset += L / v_line + 1.0;
  }
  if (rows.empty()) throw InputError("no usable width samples on the printed lines", out.photo);
  out.width_csv = dir + "/line_widths.csv";
  core::write_file_atomic(
      out.width_csv, vision::timed_width_csv(rows, "widths along the line test (t = s / v per line, lines 1 s apart)"));

  // 4. The ring: width against the angle travelled -> gain and phase at f = N v / (2 pi R).
  nlohmann::json ring_json;
  if (ring != nullptr && runs.count("liquefier-ring")) {
    const auto& rp = runs.at("liquefier-ring").experiment.params;
    const double R = rp.at("radius_mm"), v = rp.at("speed_mm_s"), A = rp.at("amplitude");
    const int N = static_cast<int>(std::lround(rp.at("periods"))),
              segs = static_cast<int>(std::lround(rp.at("segments")));
    std::vector<cv::Point2d> pts;
    std::vector<const vision::WidthSample*> valid;
    for (const auto& s : ring->samples)
      if (s.valid()) {
        pts.emplace_back(map.known ? map.x(s.x_px) : s.x_px / map.px_per_mm,
                         map.known ? map.y(s.y_px) : -s.y_px / map.px_per_mm);
        valid.push_back(&s);
      }
    if (pts.size() > 50) {
      const cv::Vec3d c = vision::fit_circle(pts);
      const double cx = map.known ? rp.at("center_x_mm") : c[0], cy = map.known ? rp.at("center_y_mm") : c[1];
      std::vector<double> t, y, ysp;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        double th = std::atan2(pts[i].y - cy, pts[i].x - cx);
        if (th < 0) th += 2 * std::numbers::pi;
        if (th < kRingSkipRad || th > 2 * std::numbers::pi - 0.05) continue;
        const int seg = std::clamp(static_cast<int>(th / (2 * std::numbers::pi) * segs), 0, segs - 1);
        const double th_mid = 2 * std::numbers::pi * (seg + 0.5) / segs;
        t.push_back(th * R / v);
        y.push_back(valid[i]->width_px / map.px_per_mm);
        ysp.push_back(profile.print.line_width_mm * (1 + A * std::sin(N * th_mid)));
      }
      const double w = N * v / R;
      if (t.size() > 50) {
        const auto fm = fit_sine_at(t, y, w), fs_ = fit_sine_at(t, ysp, w);
        const std::complex<double> H = std::complex<double>(fm.c, -fm.s) / std::complex<double>(fs_.c, -fs_.s);
        ring_json = {{"freq_hz", w / (2 * std::numbers::pi)},
                     {"gain", std::abs(H)},
                     {"phase_deg", std::arg(H) * 180 / std::numbers::pi},
                     {"samples", t.size()},
                     {"radius_mm", R},
                     {"measured_radius_mm", c[2]},
                     {"setpoint_amplitude_mm", std::hypot(fs_.c, fs_.s)},
                     {"width_amplitude_mm", std::hypot(fm.c, fm.s)}};
      } else {
        warnings.push_back("the ring has too few measured samples past its start for gain and phase");
      }
    } else {
      warnings.push_back("the ring was not measured (too few valid samples)");
    }
  } else {
    warnings.push_back("no ring found in the photo: no gain and phase from the ring test");
  }

  out.results = {{"photo", out.photo},         {"overlay", out.overlay},
                 {"px_per_mm", map.px_per_mm}, {"placement", map.known ? "camera frame" : "line end"},
                 {"lines", lines_json},        {"width_record", out.width_csv},
                 {"warnings", warnings}};
  if (!ring_json.is_null()) out.results["ring"] = ring_json;
  plot_line["overlay_png"] = fs::relative(out.overlay, run_dir).generic_string();
  out.linewidth_plot = plot_line;
  return out;
}

void add_ring_prediction(nlohmann::json& r, double K, double tau, double theta) {
  if (!r.contains("ring") || !std::isfinite(tau)) return;
  const double w = 2 * std::numbers::pi * r["ring"]["freq_hz"].get<double>();
  if (!std::isfinite(theta)) theta = 0;
  const std::complex<double> G = K * std::exp(std::complex<double>(0, -w * theta)) / std::complex<double>(1, w * tau);
  r["ring"]["model_gain"] = std::abs(G);
  r["ring"]["model_phase_deg"] = std::arg(G) * 180 / std::numbers::pi;
  // The dead time the ring's phase implies with the lines' tau: phase = -atan(w tau) - w theta.
  // It does not depend on where the lines lie on their paths (the weak point of a photo whose
  // placement on the bed is not known), only on the ring's start direction (+X).
  const double lag = -r["ring"]["phase_deg"].get<double>() * std::numbers::pi / 180 - std::atan(w * tau);
  r["ring"]["theta_from_phase_s"] = lag / w;
}

}  // namespace tunekit::calibration
