#include "tunekit/protocols/camera_prints.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

#include "experiment_gcode.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kMaxLineStepRatio = 1.55;

using experiment_gcode::num;

double line_steps_param(const std::map<std::string, double>& p, const char* k) {
  const auto it = p.find(k);
  if (it == p.end() || !(it->second > 0) || !std::isfinite(it->second))
    throw InputError(fmt::format("line-steps parameter {} must be positive", k));
  return it->second;
}

}  // namespace

double PrintedLine::length_mm() const {
  double l = 0;
  for (const auto& s : path) l += s.length_mm;
  return l;
}

std::vector<PrintedLine> line_steps_layout(const std::map<std::string, double>& p,
                                           const machine::MachineProfile& profile) {
  const double v = line_steps_param(p, "speed_mm_s");
  const double lead = line_steps_param(p, "lead_mm"), step = line_steps_param(p, "step_mm"),
               tail = line_steps_param(p, "tail_mm");
  const double lo = line_steps_param(p, "low_flow"), hi = line_steps_param(p, "high_flow");
  // The photo measurement flags a stretch wider than 1.6 times its line's median width as two
  // merged beads: a step wider than that would be dropped from the measured widths.
  if (!(std::max(hi, lo) <= kMaxLineStepRatio * std::min(hi, lo)))
    throw InputError(
        fmt::format("line-steps: high_flow {:g} and low_flow {:g} differ by more than a factor {:g} (a "
                    "photo takes a line that much wider for two merged beads)",
                    hi, lo, kMaxLineStepRatio));
  const double spacing = line_steps_param(p, "spacing_mm");
  // The first line's run-up (no extrusion, at the line's speed): 0 leaves it out.
  const double runup = p.count("rest_mm") ? std::max(0.0, p.at("rest_mm")) : 0.0;
  const int n = std::max(1, static_cast<int>(std::lround(line_steps_param(p, "lines"))));
  const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
  const double total = lead + step + tail;
  double cx = p.count("center_x_mm") ? p.at("center_x_mm") : std::nan("");
  double y0 = p.count("first_y_mm") ? p.at("first_y_mm") : std::nan("");
  const auto& ax = profile.axis("x");
  const auto& ay = profile.axis("y");
  if (std::isnan(cx)) cx = 0.5 * (ax.min_mm + ax.max_mm);
  if (std::isnan(y0)) y0 = 0.5 * (ay.min_mm + ay.max_mm) - 50;
  std::vector<PrintedLine> out;
  for (int k = 0; k < n; ++k) {
    PrintedLine l;
    l.x0_mm = cx - (total - runup) / 2;  // the lines and the first one's run-up centred together
    l.y_mm = y0 - k * spacing;
    if (k == 0 && runup > 0) {
      l.x0_mm -= runup;
      l.path.push_back({runup, v, 0.0});
    }
    for (const auto& [len, flow] : {std::pair{lead, lo}, std::pair{step, hi}, std::pair{tail, lo}})
      l.path.push_back({len, v, e_per_mm * len * flow});
    out.push_back(l);
  }
  return out;
}

void append_line_steps_gcode(std::vector<std::string>& g, const std::map<std::string, double>& p,
                             const machine::MachineProfile& profile, const firmware::Dialect& d) {
  const auto lines = line_steps_layout(p, profile);
  const double z = line_steps_param(p, "z_mm"), accel = line_steps_param(p, "accel_mm_s2");
  const double retract = p.count("retract_mm") ? std::max(0.0, p.at("retract_mm")) : 0.0;
  const double travel = std::min(100.0, profile.axis("x").max_velocity_mm_s);
  // Retraction as fast as the profile allows (the safety check counts it as flow too), at most 30 mm/s.
  const double retract_v = std::min(
      {30.0, profile.extruder.max_velocity_mm_s, 0.9 * profile.extruder.max_flow_mm3_s / profile.filament_area_mm2()});
  const std::string retract_line = fmt::format("G1 E-{} F{} ; retract", num(retract, 5), num(retract_v * 60, 1));
  const std::string prime_line = fmt::format("G1 E{} F{} ; prime", num(retract, 5), num(retract_v * 60, 1));
  const auto& last = lines.back().path;  // without the first line's run-up
  g.push_back(fmt::format("; {} lines along +X, flow steps at {} mm and {} mm", lines.size(), num(last[0].length_mm),
                          num(last[0].length_mm + last[1].length_mm)));
  g.push_back("G28");
  g.push_back("G90");
  g.push_back("M83 ; relative extrusion");
  if (p.count("hotend_c") && p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
  g.push_back(d.set_accel(std::min(accel, profile.axis("z").max_accel_mm_s2)));
  g.push_back(fmt::format("G1 Z{} F{}", num(z), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
  g.push_back(d.set_accel(accel));
  // Every line starts retracted, the first too: each travel is preceded by a retraction, so each
  // prime only restores it (a prime without one would push retract_mm of filament, about 20 mm of
  // line's worth at the defaults, out as a blob at the first line's start).
  if (retract > 0) g.push_back(retract_line);
  const double dwell = p.count("rest_dwell_s") ? std::max(0.0, p.at("rest_dwell_s")) : 0.0;
  for (const auto& l : lines) {
    g.push_back(fmt::format("G1 X{} Y{} F{}", num(l.x0_mm), num(l.y_mm), num(travel * 60, 1)));
    if (retract > 0) g.push_back(prime_line);
    // A line that begins with a run-up starts from rest: the melt the prime pushed oozes out at
    // the run-up's start while the nozzle waits, and the extrusion then starts at the line's
    // speed, so the width rises from zero (the filling the record measures the stored melt by).
    const bool from_rest = !l.path.empty() && l.path.front().feed_mm == 0;
    if (from_rest && dwell > 0)
      g.push_back(fmt::format("G4 P{} ; wait for the melt to come to rest", std::lround(dwell * 1000)));
    double x = l.x0_mm;
    for (const auto& s : l.path) {
      x += s.length_mm;
      if (s.feed_mm == 0) {
        g.push_back(fmt::format("G1 X{} F{} ; run-up", num(x), num(s.speed_mm_s * 60, 1)));
        continue;
      }
      g.push_back(fmt::format("G1 X{} E{} F{}", num(x), num(s.feed_mm, 5), num(s.speed_mm_s * 60, 1)));
    }
    if (retract > 0) g.push_back(retract_line);
  }
  g.push_back(d.wait_for_moves());
}

}  // namespace tunekit::protocols
