#include "tunekit/protocols/safety.hpp"

#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/gcode.hpp"

namespace tunekit::protocols {

std::vector<Violation> check_protocol(const std::vector<std::string>& gcode, const MachineProfile& p,
                                      const std::vector<std::string>& sensors) {
  std::vector<Violation> out;
  for (const auto& s : sensors) {
    const bool present = s == "accelerometer"      ? p.sensors.accelerometer
                         : s == "load_cell"        ? p.sensors.load_cell
                         : s == "filament_encoder" ? p.sensors.filament_encoder
                         : s == "camera"           ? p.sensors.camera
                                                   : false;
    if (!present) out.push_back({0, "", fmt::format("the protocol needs a {} and the profile has none ([sensors] {} = true)", s, s)});
  }
  GcodeInterpreter in;
  // Start at home: the axis minimums.
  {
    GcodeWords home;
    home.command = "G92";
    for (const char* a : {"x", "y", "z"})
      if (p.axes.count(a)) home.args[std::string(1, static_cast<char>(std::toupper(a[0])))] = p.axes.at(a).min_mm;
    in.apply(home);
  }
  const double tol = 1e-6;
  for (std::size_t i = 0; i < gcode.size(); ++i) {
    const auto w = parse_gcode(gcode[i]);
    if (!w) continue;
    auto add = [&](std::string what) { out.push_back({i + 1, gcode[i], std::move(what)}); };
    if (w->command == "G28") {
      GcodeWords home;
      home.command = "G92";
      for (const char* a : {"x", "y", "z"})
        if (p.axes.count(a)) home.args[std::string(1, static_cast<char>(std::toupper(a[0])))] = p.axes.at(a).min_mm;
      in.apply(home);
      continue;
    }
    const auto move = in.apply(*w);
    if ((w->command == "M104" || w->command == "M109") && in.hotend_c && *in.hotend_c > p.temperature.hotend_max_c + tol)
      add(fmt::format("hot-end temperature {:g} degC exceeds hotend_max_c {:g}", *in.hotend_c, p.temperature.hotend_max_c));
    if ((w->command == "M140" || w->command == "M190") && in.bed_c && *in.bed_c > p.temperature.bed_max_c + tol)
      add(fmt::format("bed temperature {:g} degC exceeds bed_max_c {:g}", *in.bed_c, p.temperature.bed_max_c));
    if (!move) continue;
    const auto u = move->unit();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::string name = kAxisNames[k];
      const double d = move->end[k] - move->start[k];
      if (std::abs(d) <= 1e-12 && !p.axes.count(name)) continue;
      if (!p.axes.count(name)) {
        add(fmt::format("moves axis {} which the profile does not have", name));
        continue;
      }
      const auto& a = p.axes.at(name);
      if (move->end[k] < a.min_mm - tol || move->end[k] > a.max_mm + tol)
        add(fmt::format("{} position {:g} mm is outside the travel {:g}..{:g} mm", name, move->end[k], a.min_mm, a.max_mm));
      const double v = move->feed_mm_s * std::abs(u[k]);
      if (v > a.max_velocity_mm_s + tol)
        add(fmt::format("{} speed {:.6g} mm/s exceeds max_velocity_mm_s {:g}", name, v, a.max_velocity_mm_s));
      const double acc = move->accel_mm_s2 * std::abs(u[k]);
      if (acc > a.max_accel_mm_s2 + tol)
        add(fmt::format("{} acceleration {:.6g} mm/s^2 exceeds max_accel_mm_s2 {:g}", name, acc, a.max_accel_mm_s2));
    }
    if (std::abs(move->end[3] - move->start[3]) > 1e-12) {
      const double ve = move->feed_mm_s * std::abs(u[3]);
      const double ae = move->accel_mm_s2 * std::abs(u[3]);
      const double flow = ve * p.filament_area_mm2();
      if (ve > p.extruder.max_velocity_mm_s + tol)
        add(fmt::format("filament feed {:.6g} mm/s exceeds [extruder] max_velocity_mm_s {:g}", ve, p.extruder.max_velocity_mm_s));
      if (flow > p.extruder.max_flow_mm3_s + tol)
        add(fmt::format("volumetric flow {:.6g} mm^3/s exceeds max_flow_mm3_s {:g}", flow, p.extruder.max_flow_mm3_s));
      if (ae > p.extruder.max_accel_mm_s2 + tol)
        add(fmt::format("filament acceleration {:.6g} mm/s^2 exceeds [extruder] max_accel_mm_s2 {:g}", ae, p.extruder.max_accel_mm_s2));
    }
  }
  return out;
}

void require_within_limits(const std::vector<std::string>& gcode, const MachineProfile& profile,
                           const std::vector<std::string>& sensors) {
  const auto v = check_protocol(gcode, profile, sensors);
  if (v.empty()) return;
  std::string msg = fmt::format("refused: the protocol exceeds the machine profile in {} place{} (nothing was sent): ",
                                v.size(), v.size() == 1 ? "" : "s");
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (i) msg += "; ";
    if (v[i].line) msg += fmt::format("G-code line {} '{}': ", v[i].line, v[i].gcode);
    msg += v[i].what;
  }
  throw InputError(msg, profile.source_path);
}

}  // namespace tunekit::protocols
