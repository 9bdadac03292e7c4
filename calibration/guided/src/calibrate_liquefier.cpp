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
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>

#include "tunekit/fitting/stats.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/feed_track.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/photo_widths.hpp"
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
// The line test's longest lead-in, and the room it leaves at each end of the X travel (line_lead_mm).
constexpr double kLineLeadMaxMm = 90;
constexpr double kLineClearMm = 10;
// The width record lays the lines end to end, each 1 s after the one before.
constexpr double kLineGapS = 1.0;
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
    std::string why = read_file_bytes(log);
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

// What the camera path knows about its photo: the scale (the simulated camera's frame or
// --px-per-mm), where the camera put the bed (simulated camera only) and the two printed tests.
vision::PhotoWidthsRequest camera_request(double px_per_mm, const vision::BedPlacement& placement,
                                          const protocols::RunResult& line_run,
                                          const std::vector<protocols::PrintedLine>& layout,
                                          const machine::MachineProfile& profile,
                                          const std::map<std::string, protocols::RunResult>& runs) {
  vision::PhotoWidthsRequest req;
  req.scale.px_per_mm = px_per_mm;
  req.placement = placement;
  vision::LineTest lt;
  for (const auto& pl : layout) lt.lines.push_back({pl.x0_mm, pl.path});
  lt.filament_diameter_mm = profile.extruder.filament_diameter_mm;
  lt.layer_height_mm = line_run.experiment.params.at("z_mm");
  req.line_test = lt;
  if (const auto it = runs.find("liquefier-ring"); it != runs.end()) {
    // ring-print modulates the extrusion by (1 + A sin(N theta)), theta from +X counterclockwise,
    // constant along each straight segment.
    const auto& rp = it->second.experiment.params;
    vision::RingTest ring;
    ring.sines = static_cast<int>(std::lround(rp.at("periods")));
    ring.speed_mm_s = rp.at("speed_mm_s");
    ring.radius_mm = rp.at("radius_mm");
    ring.setpoint_width_mm = profile.print.line_width_mm;
    ring.setpoint_amplitude_mm = rp.at("amplitude") * profile.print.line_width_mm;
    ring.segments = static_cast<int>(std::lround(rp.at("segments")));
    req.ring_test = ring;
  }
  return req;
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

namespace {

double protocol_default(const std::string& protocol, const std::string& param) {
  for (const auto& q : protocols::protocol_spec(protocol).params)
    if (q.name == param) return q.default_value;
  throw std::logic_error(protocol + " has no parameter " + param);
}

// The line test's lead-in (line-steps lead_mm) as long as the X travel takes, up to 90 mm. The
// photo's record keeps only its last 15 mm (the restart after the travel and the prime is left
// out, vision's photo_tests), so the lead sets how far a restart's transient has decayed by then:
// 75 mm at 20 mm/s is 3.75 s, 8 time constants of a slow (PEEK-like, 0.45 s) liquefier. The
// protocol's 45 mm left 1.5 s, 3.3 of them: on the simulated PEEK printer the width still stood
// 3 % above its level where the record started, on every line, which read tau 3.5 % low and the
// width gain 0.98 with an interval that excluded 1.
double line_lead_mm(const machine::MachineProfile& profile) {
  const auto& x = profile.axis("x");
  const double rest = protocol_default("line-steps", "step_mm") + protocol_default("line-steps", "tail_mm") +
                      protocol_default("line-steps", "rest_mm");
  return std::clamp(x.max_mm - x.min_mm - rest - 2 * kLineClearMm, protocol_default("line-steps", "lead_mm"),
                    kLineLeadMaxMm);
}

// The length along a line one width sample averages (mm): its pixel and `along_half_px` pixels
// (rounded) on each side (line_edge_profile's measure_station; the start's integrated widths alike).
double sample_averaged_mm(const vision::LineWidthOptions& o, double px_per_mm) {
  return (2.0 * std::max(0L, std::lround(o.along_half_px)) + 1) / px_per_mm;
}

// The line test's commanded feed in the width record's time (line k's path from t_k, the lines
// laid end to end 1 s apart as in the record) as the photo's width samples see it: constant over
// each segment, each change spread linearly over the length a width sample averages (its pixel
// and one on each side along the line: 3 px). A model driven by the sharp step reads the samples'
// smoothing as a slower liquefier with a shorter dead time (theta 0.45 half-widths short over 40
// seeds of the simulated camera). The step analysis drives its whole-record model by it, and a
// line that starts from rest (a run-up without extrusion) gives the instant its feed begins, for
// the melt stored at its first level. Between lines the feed is held at the level the next line
// starts at.
ident::FeedTrack line_test_feed_track(const std::vector<protocols::PrintedLine>& layout, double line_gap_s,
                                      double averaged_mm) {
  ident::FeedTrack k;
  double t = 0;
  for (const auto& line : layout) {
    double prev = std::nan("");
    for (const auto& sg : line.path) {
      const double dt = sg.length_mm / sg.speed_mm_s, rate = dt > 0 ? sg.feed_mm / dt : 0.0;
      const double half = 0.5 * averaged_mm / sg.speed_mm_s;
      if (std::isnan(prev)) {
        k.t.push_back(t), k.u.push_back(rate);
      } else if (rate != prev) {
        k.t.insert(k.t.end(), {t - half, t + half});
        k.u.insert(k.u.end(), {prev, rate});
      }
      prev = rate;
      t += dt;
    }
    k.t.push_back(t), k.u.push_back(prev);
    t += line_gap_s;
  }
  return k;
}

}  // namespace

std::vector<CameraTest> camera_tests(const machine::MachineProfile& profile) {
  // A bed too short for the protocol's own lead-in: the protocol fits its lines to the travel
  // (every length and the speed scaled together, the durations kept; machine defaults).
  std::map<std::string, double> lines;
  const auto& x = profile.axis("x");
  const double room = x.max_mm - x.min_mm - 2 * kLineClearMm - protocol_default("line-steps", "step_mm") -
                      protocol_default("line-steps", "tail_mm") - protocol_default("line-steps", "rest_mm");
  if (room >= protocol_default("line-steps", "lead_mm")) lines["lead_mm"] = line_lead_mm(profile);
  return {{"liquefier-lines", "line-steps", lines},
          {"liquefier-ring", "ring-print", {{"amplitude", kRingAmplitude}, {"periods", kRingPeriods}}}};
}

namespace {

// 1. The photo: the simulated camera's (its scale and bed placement known), or one captured from
// the device, given or asked for; kept with the run (out.photo).
cv::Mat printed_tests_photo(const std::string& dir, const LiquefierCameraArgs& a,
                            const std::shared_ptr<sim::SimPrintBed>& bed, bool can_prompt, CliContext& ctx,
                            CameraAnalysis& out, double& px_per_mm, vision::BedPlacement& placement) {
  cv::Mat photo;
  if (a.camera == "sim") {
    sim::SimCameraFrame frame;
    photo = bed->photograph(sim::SimCameraOptions{}, &frame);
    out.photo = dir + "/photo.png";
    out.photo_input = input_digest(out.photo, vision::write_png(out.photo, photo));
    px_per_mm = frame.px_per_mm;
    placement = {true, frame.x0_mm, frame.y1_mm};
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
    const std::string bytes = vision::read_image_bytes(path);
    photo = vision::decode_image(bytes, path, vision::ImageColor::gray);
    out.photo = path;
    if (path != dir + "/photo.png") {
      // The photo is kept with the run: the bytes read, written there.
      out.photo = dir + "/photo" + fs::path(path).extension().string();
      core::write_file_atomic(out.photo, bytes);
    }
    out.photo_input = input_digest(out.photo, bytes);
  }
  return photo;
}

}  // namespace

CameraAnalysis analyze_camera_prints(const std::string& run_dir, const LiquefierCameraArgs& a,
                                     const machine::MachineProfile& profile,
                                     const std::map<std::string, protocols::RunResult>& runs,
                                     const std::shared_ptr<sim::SimPrintBed>& bed, bool can_prompt, CliContext& ctx) {
  const std::string dir = run_dir + "/liquefier-camera";
  fs::create_directories(dir);
  CameraAnalysis out;
  double px_per_mm = a.px_per_mm;
  vision::BedPlacement placement;  // known for the simulated camera only

  // 1. The photo.
  const cv::Mat photo = printed_tests_photo(dir, a, bed, can_prompt, ctx, out, px_per_mm, placement);

  // 2. The lines and the ring in it: one measurement, the same as `tunekit linewidth`'s.
  const auto& line_run = runs.at("liquefier-lines");
  const auto layout = protocols::line_steps_layout(line_run.experiment.params, profile);
  const auto pw = vision::measure_photo_widths(
      photo, camera_request(px_per_mm, placement, line_run, layout, profile, runs), out.photo);
  out.overlay = dir + "/overlay.png";
  if (pw.features.lines.empty()) {
    vision::write_overlay(out.overlay, vision::draw_overlay(photo, &pw.features, {}, "no printed line found"));
    throw InputError(
        "the photo shows no printed line (is the print in the frame, in focus and lit?); the printed runs "
        "are kept in " +
            run_dir,
        out.photo);
  }
  vision::write_overlay(out.overlay, vision::draw_overlay(photo, &pw.features, {}, ""));
  if (!pw.failure.empty()) throw InputError(pw.failure, out.photo);
  nlohmann::json warnings = pw.warnings;

  // 3. Widths along the lines -> one time record (line k starts 1 s after line k-1 ends).
  const double v_line = layout.front().path.front().speed_mm_s;
  std::vector<vision::TimedWidth> rows;
  nlohmann::json lines_json = nlohmann::json::array();
  double t_offset = 0;
  LinewidthPlot plot_line;
  for (std::size_t k = 0; k < pw.line_test.size(); ++k) {
    const auto& lt = pw.line_test[k];
    for (auto r : lt.rows) {
      if (k == 0) {
        plot_line.s_mm.push_back(r.s_mm);
        plot_line.width_mm.push_back(r.width_mm);
        plot_line.setpoint_mm.push_back(r.setpoint_mm);
      }
      r.t_s += t_offset;
      rows.push_back(r);
    }
    lines_json.push_back({{"line", k + 1},
                          {"y_mm", layout[k].y_mm},
                          {"samples", lt.rows.size()},
                          {"mean_width_mm", lt.mean_width_mm},
                          {"median_width_mm", lt.median_width_mm},
                          {"placement", lt.placed_by_camera ? "camera frame" : "line end"}});
    t_offset += layout[k].length_mm() / v_line + kLineGapS;
  }
  out.width_csv = dir + "/line_widths.csv";
  // Beside the record, where `tunekit step` finds it.
  out.feed_track_csv = dir + "/feed_track.csv";
  out.feed_track = InputFile::from_bytes(
      out.feed_track_csv, ident::feed_track_csv(line_test_feed_track(
                              layout, kLineGapS, sample_averaged_mm(vision::LineWidthOptions{}, pw.scale.px_per_mm))));
  core::write_file_atomic(out.feed_track_csv, out.feed_track.bytes());
  out.width_record = InputFile::from_bytes(
      out.width_csv, vision::timed_width_csv(rows, "widths along the line test (t = s / v per line, lines 1 s apart)"));
  core::write_file_atomic(out.width_csv, out.width_record.bytes());

  // 4. The ring: width against the angle travelled -> gain and phase at f = N v / (2 pi R).
  nlohmann::json ring_json;
  if (pw.ring) ring_json = vision::to_json(*pw.ring);

  out.results = {{"photo", out.photo},
                 {"overlay", out.overlay},
                 {"px_per_mm", pw.scale.px_per_mm},
                 {"placement", placement.known ? "camera frame" : "line end"},
                 {"lines", lines_json},
                 {"width_record", out.width_csv},
                 {"warnings", warnings}};
  if (!ring_json.is_null()) out.results["ring"] = ring_json;
  out.ring = pw.ring;
  out.warnings = pw.warnings;
  plot_line.overlay_png = fs::relative(out.overlay, run_dir).generic_string();
  out.linewidth_plot = plot_line;
  return out;
}

void add_ring_prediction(CameraAnalysis& camera, const RingModel& model) {
  if (!camera.ring || !std::isfinite(model.tau_s)) return;
  camera.ring_prediction =
      ident::predict_ring(model, {camera.ring->freq_hz, camera.ring->phase_deg, camera.ring->phase_stderr_deg});
}

}  // namespace tunekit::calibration
