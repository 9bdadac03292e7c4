// tunekit linewidth: calibrated width profiles of printed lines from photos.
//
// Scale comes from --px-per-mm, a camera profile (--camera, written by --save-camera), a
// chessboard in the scene (--chessboard/--square-mm, optionally --rectify for a tilted
// camera) or a line of known width (--reference-width-mm). Each line's profile (arc length,
// width, edge confidence, flags) goes to the JSON envelope; --profile-csv maps one line to
// time with the commanded speed (constant, or Holtrup's (2019) sine-modulated ring) and writes the
// set-point width the feed implied, ready for `tunekit freq` / `tunekit step`.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "linewidth_profile_csv.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/analyses/linewidth_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/vision/camera_calibration.hpp"
#include "tunekit/vision/charuco.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/overlay.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/machine/gcode.hpp"

namespace tunekit::calibration {

// The ring test as given: Holtrup's (2019) feeder modulation (eq. 4.3: amplitude from the feeder
// offset, rod radius and layer height, -cos in time) or tunekit's ring-print flow modulation
// (1 + A sin(N theta)), with what the photo cannot tell (speed, start, direction).
vision::RingTest linewidth::ring_test(const LinewidthOptions& a) {
  vision::RingTest t;
  t.sines = a.ring_sines;
  t.speed_mm_s = a.speed_mm_s;
  t.radius_mm = a.ring_radius_mm;
  t.setpoint_width_mm = a.setpoint_width_mm;
  t.segments = a.ring_segments;
  t.start_deg = a.ring_start_deg;
  t.clockwise = a.ring_clockwise;
  if (a.ring_flow_amplitude > 0) {
    t.setpoint_amplitude_mm = a.ring_flow_amplitude * a.setpoint_width_mm;
    return t;
  }
  vision::RingSine hs;  // eq. 4.3's amplitude at R = 1 mm: a R
  hs.n_sines = a.ring_sines;
  hs.amplitude_mm = a.ring_amplitude_mm;
  hs.radius_mm = 1;
  hs.rod_radius_mm = a.rod_radius_mm;
  hs.layer_height_mm = a.layer_height_mm;
  t.setpoint_amplitude_mm2 = vision::ring_setpoint_amplitude_mm(hs);
  t.setpoint_phase_deg = -90;  // -cos(x) = sin(x - 90 deg)
  return t;
}

namespace {

using linewidth::ImageRun;
using linewidth::r4;
using linewidth::r6;

std::string flag_names(std::uint8_t f) {
  std::string s;
  auto add = [&](const char* n) { s += (s.empty() ? "" : ","), s += n; };
  if (f & vision::kFlagOutOfFrame) add("out_of_frame");
  if (f & vision::kFlagOccluded) add("occluded");
  if (f & vision::kFlagMerged) add("merged");
  return s;
}

// Contiguous flagged stretches of a line, in mm of arc length.
nlohmann::json stretches(const vision::MeasuredLine& l, double ppm) {
  nlohmann::json out = nlohmann::json::array();
  const auto& s = l.samples;
  std::size_t i = 0;
  while (i < s.size()) {
    if (s[i].flags == 0) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j + 1 < s.size() && s[j + 1].flags == s[i].flags) ++j;
    out.push_back({{"flags", flag_names(s[i].flags)},
                   {"s_start_mm", r6(s[i].s_px / ppm)},
                   {"s_end_mm", r6(s[j].s_px / ppm)},
                   {"samples", j - i + 1}});
    i = j + 1;
  }
  return out;
}

std::string overlay_path(const std::string& dir, const std::string& image) {
  return (std::filesystem::path(dir) / (std::filesystem::path(image).stem().string() + "_overlay.png")).string();
}

// Writes the overlay if asked; never lets a write failure hide the original error.
void overlay_best_effort(const LinewidthOptions& a, const ImageRun& run, const vision::LineWidthResult* res,
                         const std::string& message, std::ostream& err) {
  if (a.overlay_dir.empty()) return;
  try {
    std::filesystem::create_directories(a.overlay_dir);
    vision::write_overlay(overlay_path(a.overlay_dir, run.path),
                          vision::draw_overlay(run.measured, res, run.target_outline, message));
  } catch (const std::exception& e) {
    err << fmt::format("tunekit: warning: overlay not written: {}\n", e.what());
  }
}

vision::PhotoWidthsRequest photo_request(const LinewidthOptions& a, const std::optional<vision::CameraProfile>& cam) {
  vision::PhotoWidthsRequest req;
  auto& sc = req.scale;
  sc.camera = cam;
  if (!a.charuco.empty()) sc.charuco = vision::parse_charuco_spec(a.charuco, a.square_mm, a.marker_mm, a.aruco_dict);
  else if (!a.chessboard.empty()) sc.chessboard = vision::parse_chessboard_spec(a.chessboard, a.square_mm);
  sc.px_per_mm = a.px_per_mm;
  sc.nominal_width_mm = a.reference_width_mm;
  sc.rectify = a.rectify;
  req.detection = a.detection;
  if (a.ring_sines > 0) req.ring_test = linewidth::ring_test(a);
  return req;
}

// Throws the error of a photo that gave no measurement, after its overlay.
void check_measured(const LinewidthOptions& a, const ImageRun& run, std::ostream& err) {
  const auto& res = run.result;
  if (res.lines.empty()) {
    std::string msg = "no line found";
    for (const auto& w : res.warnings) msg += ": " + w;
    overlay_best_effort(a, run, &res, msg, err);
    throw FitError(msg, run.path);
  }
  if (!a.allow_edge) {
    for (std::size_t i = 0; i < res.lines.size(); ++i)
      if (res.lines[i].touches_frame) {
        const auto& b = res.lines[i].bbox;
        const std::string msg = fmt::format(
            "line {} touches the frame edge (it spans x {}..{}, y {}..{} px of {}x{}); reframe the photo "
            "or pass --allow-edge to measure it with out-of-frame stretches flagged",
            i + 1, b.x, b.x + b.width, b.y, b.y + b.height, res.width, res.height);
        overlay_best_effort(a, run, &res, msg, err);
        throw InputError(msg, run.path);
      }
  }
  int valid = 0;
  for (const auto& l : res.lines) valid += l.valid_samples;
  if (valid == 0) {
    const std::string msg = "measured nothing: every profile sample is flagged (occluded, merged or out of frame)";
    overlay_best_effort(a, run, &res, msg, err);
    throw FitError(msg, run.path);
  }
}

// `bytes`: the image file's, read once (their digest is the input's).
ImageRun measure_image(const LinewidthOptions& a, const std::string& path, const std::string& bytes,
                       const std::optional<vision::CameraProfile>& cam, std::ostream& err) {
  auto pw = vision::measure_photo_widths(vision::gray_image_from_bytes(bytes, path), photo_request(a, cam), path);
  ImageRun run;
  run.path = path;
  run.measured = pw.measured;
  run.ppm = pw.scale.px_per_mm;
  run.scale = pw.scale;
  run.target_outline = pw.target_outline;
  run.result = std::move(pw.features);
  run.lines = std::move(pw.lines);
  run.ring = pw.ring;
  run.warnings = std::move(pw.warnings);
  if (!pw.failure.empty()) {
    overlay_best_effort(a, run, run.result.lines.empty() ? nullptr : &run.result, pw.failure, err);
    throw InputError(pw.failure, path);
  }
  check_measured(a, run, err);
  overlay_best_effort(a, run, &run.result, "", err);
  return run;
}

LinewidthOutcome compute_linewidth_camera(const LinewidthOptions& a) {
  if (a.chessboard.empty()) throw InputError("--save-camera needs --chessboard COLSxROWS and --square-mm");
  const auto spec = vision::parse_chessboard_spec(a.chessboard, a.square_mm);
  LinewidthOutcome outcome;
  outcome.options = a;
  std::vector<cv::Mat> grays;
  for (const auto& p : a.images) {
    const std::string bytes = vision::read_image_bytes(p);
    grays.push_back(vision::gray_image_from_bytes(bytes, p));
    outcome.inputs.push_back(input_digest(p, bytes));
  }
  std::vector<int> skipped;
  outcome.camera = vision::calibrate_camera(grays, spec, &skipped);
  for (int i : skipped)
    outcome.warnings.push_back(fmt::format("{}: {}x{} chessboard not found; image not used",
                                           a.images[static_cast<std::size_t>(i)], spec.cols, spec.rows));
  core::write_file_atomic(a.save_camera, outcome.camera->to_json().dump(2) + "\n");
  return outcome;
}

std::string linewidth_polarity_name(vision::LinePolarity p) {
  return p == vision::LinePolarity::dark ? "dark" : p == vision::LinePolarity::light ? "light" : "auto";
}

}  // namespace

LinewidthOutcome compute_linewidth(const LinewidthOptions& a, std::ostream& err) {
  if (!(a.max_image_mp > 0 && a.max_image_mp <= 1e5))
    throw InputError("--max-image-mp must be in (0, 100000] megapixels");
  vision::set_max_image_pixels(static_cast<std::uint64_t>(std::ceil(a.max_image_mp * 1e6)));
  if (!a.save_camera.empty()) return compute_linewidth_camera(a);
  const bool board = !a.chessboard.empty() || !a.charuco.empty();
  if (!a.chessboard.empty() && !a.charuco.empty()) throw InputError("give --chessboard or --charuco, not both");
  if (!a.charuco.empty() && !(a.marker_mm > 0)) throw InputError("--charuco needs --square-mm and --marker-mm (mm)");
  const int scales = (a.px_per_mm > 0) + !a.camera.empty() + board + (a.reference_width_mm > 0);
  if (scales == 0)
    throw InputError(
        "no scale: give --px-per-mm, --camera PROFILE, --chessboard COLSxROWS --square-mm S, or "
        "--reference-width-mm W");
  if ((a.px_per_mm > 0) + (a.reference_width_mm > 0) + board > 1)
    throw InputError("give only one of --px-per-mm, --chessboard (or --charuco) and --reference-width-mm");
  if (a.rectify && !board && a.camera.empty())
    throw InputError("--rectify needs --chessboard, --charuco or a --camera profile with a bed plane");
  if (board && !(a.square_mm > 0)) throw InputError("--chessboard and --charuco need --square-mm (mm)");
  if (!a.profile_csv.empty() && a.images.size() != 1)
    throw InputError("--profile-csv maps one image's line to time: give exactly one image");
  if (!a.profile_csv.empty() && !(a.speed_mm_s > 0) && a.gcode.empty())
    throw InputError("--profile-csv needs the commanded print speed: --speed-mm-s (mm/s) or --gcode FILE");
  if (!a.gcode.empty() && a.profile_csv.empty()) throw InputError("--gcode maps a profile to time: add --profile-csv");
  if (!a.gcode.empty() && a.ring_sines > 0)
    throw InputError("give either --gcode or the ring's --ring-sines, not both");
  const bool feeder_ring = a.ring_amplitude_mm > 0 && a.rod_radius_mm > 0 && a.layer_height_mm > 0;
  if (a.ring_sines > 0 && feeder_ring == (a.ring_flow_amplitude > 0))
    throw InputError(
        "--ring-sines needs one modulation: Holtrup's feeder (--ring-amplitude-mm, --rod-radius-mm and "
        "--layer-height-mm) or the extrusion's (--ring-flow-amplitude with --setpoint-width-mm)");
  if (a.ring_flow_amplitude > 0 && !(a.setpoint_width_mm > 0))
    throw InputError("--ring-flow-amplitude needs --setpoint-width-mm (the ring's mean line width, mm)");
  if (a.ring_sines > 0 && !(a.speed_mm_s > 0))
    throw InputError("--ring-sines needs the print speed around the ring: --speed-mm-s (mm/s)");

  LinewidthOutcome outcome;
  outcome.options = a;
  std::optional<vision::CameraProfile> cam;
  if (!a.camera.empty()) {
    const InputFile profile = InputFile::read(a.camera);
    cam = vision::parse_camera_profile(profile.bytes(), a.camera);
    outcome.inputs.push_back(profile.digest());
    if (!cam->has_bed_plane && a.px_per_mm <= 0 && !board && a.reference_width_mm <= 0)
      throw InputError("camera profile has no bed plane scale: add --px-per-mm, --chessboard or --reference-width-mm",
                       a.camera);
  }
  std::vector<ImageRun> runs;
  for (const auto& path : a.images) {
    const std::string bytes = vision::read_image_bytes(path);
    runs.push_back(measure_image(a, path, bytes, cam, err));
    outcome.inputs.push_back(input_digest(path, bytes));
    const auto& run = runs.back();
    const auto& res = run.result;
    for (const auto& w : run.warnings) outcome.warnings.push_back(fmt::format("{}: {}", path, w));
    for (std::size_t k = 0; k < res.lines.size(); ++k) {
      const auto& l = res.lines[k];
      const double valid_frac = l.samples.empty() ? 0.0 : static_cast<double>(l.valid_samples) / l.samples.size();
      if (valid_frac < 0.5)
        outcome.warnings.push_back(
            fmt::format("{}: line {}: only {:.0f} % of the profile is measured", path, k + 1, 100 * valid_frac));
    }
    outcome.images.push_back({run.path, run.ppm, run.scale, run.result, run.lines, run.ring});
  }
  if (!a.profile_csv.empty())
    outcome.profile_csv = linewidth::write_profile_csv(a, runs.front(), outcome.warnings, outcome.inputs);
  return outcome;
}

namespace {

// Line k of an image: its geometry, width statistics in mm and px, stretches and the profile.
nlohmann::json line_json(const LinewidthImage& run, std::size_t k) {
  const auto& res = run.result;
  const double ppm = run.px_per_mm;
  const auto& l = res.lines[k];
  nlohmann::json s_mm = nlohmann::json::array(), w_mm = nlohmann::json::array(), conf = nlohmann::json::array(),
                 flags = nlohmann::json::array(), xs = nlohmann::json::array(), ys = nlohmann::json::array();
  for (const auto& s : l.samples) {
    s_mm.push_back(r6(s.s_px / ppm));
    w_mm.push_back(s.valid() || (std::isfinite(s.width_px) && s.flags == vision::kFlagMerged)
                       ? nlohmann::json(r6(s.width_px / ppm))
                       : nlohmann::json(nullptr));
    conf.push_back(r4(s.confidence));
    flags.push_back(s.flags);
    xs.push_back(r4(s.x_px));
    ys.push_back(r4(s.y_px));
  }
  const double med = run.lines[k].median_mm;
  return nlohmann::json(
      {{"image", run.path},
       {"index", k + 1},
       {"closed", l.closed},
       {"touches_frame", l.touches_frame},
       {"length_mm", r6(l.length_px / ppm)},
       {"samples", l.samples.size()},
       {"valid_samples", l.valid_samples},
       {"width_mm",
        {{"mean", r6(l.mean_width_px / ppm)}, {"std", r6(l.std_width_px / ppm)}, {"median", r6(med)}, {"unit", "mm"}}},
       {"width_px", {{"mean", r4(l.mean_width_px)}, {"std", r4(l.std_width_px)}}},
       {"stretches", stretches(l, ppm)},
       {"profile",
        {{"s_mm", s_mm}, {"width_mm", w_mm}, {"confidence", conf}, {"flags", flags}, {"x_px", xs}, {"y_px", ys}}}});
}

// The options of a measurement (not a camera calibration), as the envelope records them.
nlohmann::json measurement_options(const LinewidthOptions& a) {
  return {
      {"px_per_mm", a.px_per_mm},
      {"camera", a.camera},
      {"chessboard", a.chessboard},
      {"charuco", a.charuco},
      {"marker_mm", a.marker_mm},
      {"aruco_dict", a.aruco_dict},
      {"square_mm", a.square_mm},
      {"reference_width_mm", a.reference_width_mm},
      {"rectify", a.rectify},
      {"polarity", linewidth_polarity_name(a.detection.polarity)},
      {"step_px", a.detection.step_px},
      {"min_length_px", a.detection.min_length_px},
      {"allow_edge", a.allow_edge},
      {"overlay", a.overlay_dir},
      {"profile_csv", a.profile_csv},
      {"line", a.line},
      {"speed_mm_s", a.speed_mm_s},
      {"setpoint_width_mm", a.setpoint_width_mm},
      {"ring_sines", a.ring_sines},
      {"ring_amplitude_mm", a.ring_amplitude_mm},
      {"ring_radius_mm", a.ring_radius_mm},
      {"rod_radius_mm", a.rod_radius_mm},
      {"layer_height_mm", a.layer_height_mm},
      {"ring_flow_amplitude", a.ring_flow_amplitude},
      {"ring_segments", a.ring_segments},
      {"ring_start_deg", a.ring_start_deg},
      {"ring_clockwise", a.ring_clockwise},
      {"gcode", a.gcode},
      {"filament_diameter_mm", a.path.filament_diameter_mm},
      {"path_offset_mm", std::isfinite(a.path.offset_mm) ? nlohmann::json(a.path.offset_mm) : nlohmann::json(nullptr)},
      {"path_reversed", a.path.reversed}};
}

}  // namespace

Envelope to_envelope(const LinewidthOutcome& o) {
  const LinewidthOptions& a = o.options;
  Envelope env("linewidth");
  for (const auto& d : o.inputs) add_input(env, d);
  for (const auto& w : o.warnings) env.warn(w);
  if (o.camera) {
    env.set_options({{"chessboard", a.chessboard}, {"square_mm", a.square_mm}, {"save_camera", a.save_camera}});
    env.results()["camera"] = o.camera->to_json();
    env.results()["camera_profile_path"] = a.save_camera;
    return env;
  }
  nlohmann::json images = nlohmann::json::array();
  nlohmann::json lines = nlohmann::json::array();
  for (const auto& run : o.images) {
    const auto& res = run.result;
    const double ppm = run.px_per_mm;
    images.push_back({{"file", run.path},
                      {"width_px", res.width},
                      {"height_px", res.height},
                      {"px_per_mm", r6(ppm)},
                      {"scale_source", run.scale.name},
                      {"scale_reason", run.scale.reason},
                      {"scale_passed_over", run.scale.passed_over},
                      {"polarity", res.light_lines ? "light" : "dark"},
                      {"noise", r4(res.noise_sigma)},
                      {"lines_found", res.lines.size()}});
    for (std::size_t k = 0; k < res.lines.size(); ++k) {
      lines.push_back(line_json(run, k));
    }
  }
  auto& results = env.results();
  results["images"] = images;
  results["lines"] = lines;
  results["flag_bits"] = {
      {"out_of_frame", vision::kFlagOutOfFrame}, {"occluded", vision::kFlagOccluded}, {"merged", vision::kFlagMerged}};
  if (!o.profile_csv.is_null()) results["profile_csv"] = o.profile_csv;
  for (const auto& run : o.images)
    if (run.ring) {
      const auto& r = *run.ring;
      results["ring"] = vision::to_json(r);
      results["ring"]["image"] = run.path;
      results["ring"]["line"] = r.feature + 1;
      results["ring"]["centre_px"] = {r4(r.centre_px.x), r4(r.centre_px.y)};
      break;
    }

  env.set_options(measurement_options(a));
  return env;
}

void print_text(const LinewidthOutcome& o, std::ostream& os) {
  if (o.camera) {
    os << fmt::format("camera profile {}: {} images, reprojection RMS {:.3f} px, bed scale {:.4f} px/mm\n",
                      o.options.save_camera, o.camera->images_used, o.camera->rms_reprojection_px, o.camera->px_per_mm);
    return;
  }
  for (const auto& run : o.images)
    for (std::size_t k = 0; k < run.result.lines.size(); ++k) {
      const auto& l = run.result.lines[k];
      const double ppm = run.px_per_mm;
      os << fmt::format("{} line {}: width {:.4f} mm (std {:.4f} mm), {} of {} samples, length {:.2f} mm{}\n", run.path,
                        k + 1, r6(l.mean_width_px / ppm), r6(l.std_width_px / ppm), l.valid_samples, l.samples.size(),
                        r6(l.length_px / ppm), l.closed ? " (closed loop)" : "");
    }
  for (const auto& run : o.images)
    if (run.ring) {
      const auto& r = *run.ring;
      os << fmt::format("{} ring (line {}) at {} Hz: gain {} {}, phase {} deg {}\n", run.path, r.feature + 1,
                        display_number(r.freq_hz), display_number(r.gain),
                        display_interval(r.gain_ci95[0], r.gain_ci95[1]), display_number(r.phase_deg),
                        display_interval(r.phase_ci95_deg[0], r.phase_ci95_deg[1]));
      break;
    }
  if (!o.profile_csv.is_null())
    os << fmt::format("profile written to {} ({} rows)\n", o.options.profile_csv,
                      o.profile_csv["rows"].get<std::size_t>());
}

}  // namespace tunekit::calibration
