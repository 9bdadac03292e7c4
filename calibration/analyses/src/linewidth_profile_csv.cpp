// tunekit linewidth --profile-csv: one measured line's width profile mapped to time with the
// commanded speed (constant, Holtrup's (2019) sine-modulated ring, or the extruding moves of a
// G-code file), written as CSV with the set-point width for `tunekit step` / `tunekit freq`.

#include <cmath>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "linewidth_profile_csv.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/vision/photo_widths.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration::linewidth {
namespace {

// The extruding moves of a G-code file, in order (travel and extruder-only moves are skipped).
std::vector<vision::PathSegment> gcode_path(const std::string& path, std::size_t& lines_read, std::string& text) {
  text = read_file_bytes(path);
  machine::GcodeInterpreter gi;
  std::vector<vision::PathSegment> segs;
  std::size_t lineno = 0, start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++lineno;
    const std::string_view line(text.data() + start, end - start);
    try {
      if (const auto w = machine::parse_gcode(line)) {
        if (const auto m = gi.apply(*w)) {
          const double de = m->end[3] - m->start[3];
          if (!m->extruder_only() && de > 0 && m->length_mm() > 0) segs.push_back({m->length_mm(), m->feed_mm_s, de});
        }
      }
    } catch (const Error& e) {
      throw InputError(e.message(), source_location(path, lineno));
    }
    start = end + 1;
  }
  lines_read = lineno;
  if (segs.empty()) throw InputError("no extruding moves (G1 with X/Y and a positive E) in the G-code file", path);
  return segs;
}

}  // namespace

nlohmann::json write_profile_csv(const LinewidthOptions& a, const ImageRun& run, std::vector<std::string>& warnings,
                                 std::vector<InputDigest>& inputs) {
  if (a.line < 1 || a.line > static_cast<int>(run.result.lines.size()))
    throw InputError(fmt::format("--line {}: the image has {} line(s)", a.line, run.result.lines.size()));
  const auto& l = run.result.lines[static_cast<std::size_t>(a.line - 1)];
  const auto& cl = run.lines[static_cast<std::size_t>(a.line - 1)];  // its widths in mm
  const std::vector<double>&w_mm = cl.width_mm, &conf = cl.confidence, &s_mm = cl.s_mm;
  const double mean_mm = cl.mean_mm;
  double setpoint = a.setpoint_width_mm;
  const bool setpoint_from_feed = !a.gcode.empty() && a.path.filament_diameter_mm > 0 && a.layer_height_mm > 0;
  if (!(setpoint > 0) && !setpoint_from_feed) {
    setpoint = mean_mm;
    warnings.push_back(
        fmt::format("no --setpoint-width-mm: the set-point width is taken as the measured mean {:.4f} mm", mean_mm));
  }
  std::vector<vision::TimedWidth> rows;
  nlohmann::json mapping;
  std::string comment;
  if (!a.gcode.empty()) {
    if (l.closed) throw InputError(fmt::format("line {} is a closed loop; --gcode maps open lines", a.line));
    std::size_t nlines = 0;
    std::string gcode_bytes;
    const auto segs = gcode_path(a.gcode, nlines, gcode_bytes);
    inputs.push_back(input_digest(a.gcode, gcode_bytes));
    vision::PathMapping how = a.path;
    how.layer_height_mm = a.layer_height_mm;
    how.setpoint_width_mm = setpoint;
    const bool from_feed = a.path.filament_diameter_mm > 0 && a.layer_height_mm > 0;
    double total = 0, duration = 0;
    for (const auto& sg : segs) {
      total += sg.length_mm;
      duration += sg.length_mm / sg.speed_mm_s;
    }
    const double prof_len = s_mm.empty() ? 0.0 : s_mm.back() - s_mm.front();
    const double offset = std::isfinite(a.path.offset_mm) ? a.path.offset_mm : 0.5 * (total - prof_len);
    if (prof_len > total * 1.05)
      warnings.push_back(
          fmt::format("the measured line ({:.2f} mm) is longer than the G-code's extruding path ({:.2f} mm): "
                      "wrong file, scale or line?",
                      prof_len, total));
    rows = vision::map_path(s_mm, w_mm, conf, segs, how);
    mapping = {{"kind", "gcode"},
               {"gcode", a.gcode},
               {"segments", segs.size()},
               {"path_length_mm", r6(total)},
               {"path_duration_s", r6(duration)},
               {"profile_length_mm", r6(prof_len)},
               {"offset_mm", r6(offset)},
               {"reversed", a.path.reversed},
               {"setpoint", from_feed ? "feed" : "constant"}};
    if (from_feed) {
      mapping["filament_diameter_mm"] = a.path.filament_diameter_mm;
      mapping["layer_height_mm"] = a.layer_height_mm;
    }
    comment = fmt::format(
        "tunekit linewidth: profile of {} (line {}) along the extruding moves of {} ({} segments, {:.3f} mm)\n"
        "setpoint_width: {}",
        run.path, a.line, a.gcode, segs.size(), total,
        from_feed
            ? fmt::format("E (pi d^2/4) / (L h), d = {} mm, h = {} mm", a.path.filament_diameter_mm, a.layer_height_mm)
            : fmt::format("constant {} mm", setpoint));
  } else if (a.ring_sines > 0) {
    if (!vision::looks_like_ring(l))
      throw InputError(fmt::format("line {} is not a ring; --ring-sines needs one", a.line));
    // The ring's own measurement: the samples it fits (past the ring's start) are the rows.
    vision::RingTest test = ring_test(a);
    test.setpoint_width_mm = setpoint;
    const auto ring = vision::measure_ring(l, run.ppm, test, warnings);
    if (!ring) throw FitError("measured nothing: too few valid ring samples to map to time", run.path);
    rows = ring->rows;
    mapping = {{"kind", "ring"},
               {"frequency_hz", r6(ring->freq_hz)},
               {"setpoint_amplitude_mm", r6(ring->setpoint_amplitude_mm)},
               {"ring_radius_mm", r6(ring->radius_mm)},
               {"measured_radius_mm", r6(ring->measured_radius_mm)},
               {"centre_px", {r4(ring->centre_px.x), r4(ring->centre_px.y)}},
               {"start_deg", a.ring_start_deg},
               {"skipped_start_deg", r6(ring->skipped_start_rad * 180 / std::numbers::pi)},
               {"direction", a.ring_clockwise ? "clockwise" : "counterclockwise"}};
    comment = fmt::format(
        "tunekit linewidth: ring profile of {} (line {}), N={} v={} mm/s R={:.4f} mm -> f={:.6g} Hz, from "
        "theta = {:.4g} rad\nsetpoint_width: {}",
        run.path, a.line, a.ring_sines, a.speed_mm_s, ring->radius_mm, ring->freq_hz, ring->skipped_start_rad,
        a.ring_flow_amplitude > 0 ? fmt::format("w (1 + {} sin(N theta))", a.ring_flow_amplitude)
                                  : fmt::format("Holtrup 2019 eq. 4.3, A={} mm", a.ring_amplitude_mm));
  } else {
    rows = vision::map_constant_speed(s_mm, w_mm, conf, a.speed_mm_s, setpoint);
    mapping = {{"kind", "constant_speed"}};
    comment =
        fmt::format("tunekit linewidth: profile of {} (line {}) at a constant {} mm/s", run.path, a.line, a.speed_mm_s);
  }
  if (rows.size() < 3) throw FitError("measured nothing: fewer than 3 valid profile samples to map to time", run.path);
  core::write_file_atomic(a.profile_csv, vision::timed_width_csv(rows, comment));
  mapping["path"] = a.profile_csv;
  mapping["rows"] = rows.size();
  mapping["line"] = a.line;
  mapping["speed_mm_s"] = a.speed_mm_s;
  mapping["setpoint_width_mm"] = r6(setpoint);
  mapping["duration_s"] = r6(rows.back().t_s - rows.front().t_s);
  return mapping;
}

}  // namespace tunekit::calibration::linewidth
