// The printed protocols: a ring with modulated extrusion (ring-print), line steps (line-steps) and
// the camera's test patterns (test-pattern), printed for the camera to measure.
#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/trajectory.hpp"

#include "experiment_gcode.hpp"

namespace tunekit::protocols::experiment_gcode {

namespace {

// The start of a printed test: homed, absolute positions, relative extrusion, the hot end heated
// (when a temperature is given), the first layer's height reached at the z axis' acceleration
// and speed, then `accel` for the print.
void print_prologue(std::vector<std::string>& g, const std::map<std::string, double>& p,
                    const machine::MachineProfile& profile, const firmware::Dialect& d, double accel) {
  g.push_back("G28");
  g.push_back("G90");
  g.push_back("M83 ; relative extrusion");
  if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
  g.push_back(d.set_accel(std::min(accel, profile.axis("z").max_accel_mm_s2)));
  g.push_back(
      fmt::format("G1 Z{} F{}", num(p.at("z_mm")), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
  g.push_back(d.set_accel(accel));
}

// Holtrup's ring: segs straight moves around a circle of radius R, the extrusion of each
// modulated by (1 + A sin(N theta)) at its middle.
void build_ring_print(const ExperimentRequest& r, Experiment& e) {
  const machine::MachineProfile& profile = r.profile;
  auto& p = e.params;
  auto& g = e.gcode;
  const double R = p.at("radius_mm"), v = p.at("speed_mm_s"), A = p.at("amplitude");
  if (A >= 1)
    throw InputError(
        fmt::format("ring-print parameter amplitude must be below 1 so the extrusion stays positive, not {:g}", A));
  const int N = static_cast<int>(p.at("periods"));
  const int segs = std::max(12, static_cast<int>(p.at("segments")));
  check_plan(r.protocol, segs + 12.0, 2 * std::numbers::pi * R / v, r.limits);
  if (std::isnan(p["center_x_mm"])) p["center_x_mm"] = mid(profile, "x");
  if (std::isnan(p["center_y_mm"])) p["center_y_mm"] = mid(profile, "y");
  const double cx = p["center_x_mm"], cy = p["center_y_mm"];
  const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
  g.push_back(fmt::format("; f = N v / (2 pi R) = {} Hz", num(N * v / (2 * std::numbers::pi * R), 4)));
  print_prologue(g, p, profile, r.dialect, p.at("accel_mm_s2"));
  g.push_back(fmt::format("G1 X{} Y{} F{}", num(cx + R), num(cy), num(std::min(100.0, v * 3) * 60, 1)));
  const double seg_len = 2 * R * std::sin(std::numbers::pi / segs);
  for (int k = 1; k <= segs; ++k) {
    const double th = 2 * std::numbers::pi * k / segs, th_mid = 2 * std::numbers::pi * (k - 0.5) / segs;
    const double de = e_per_mm * seg_len * (1 + A * std::sin(N * th_mid));
    g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(cx + R * std::cos(th)), num(cy + R * std::sin(th)), num(de, 5),
                            num(v * 60, 1)));
  }
  g.push_back(r.dialect.wait_for_moves());
}

// The test patterns' set and motion from the parameters; the retraction's filament speed kept
// within the hot end's flow and the extruder's speed (the safety check counts it against them).
std::pair<TestPatternSet, CoverageMotion> pattern_set_and_motion(const std::map<std::string, double>& p,
                                                                 const machine::MachineProfile& profile) {
  TestPatternSet set;
  set.pads = static_cast<int>(std::lround(p.at("pads")));
  set.pad_mm = p.at("pad_mm");
  set.line_steps = static_cast<int>(std::lround(p.at("line_steps")));
  set.line_mm = p.at("line_mm");
  set.rings = static_cast<int>(std::lround(p.at("rings")));
  set.ring_radius_mm = p.at("ring_radius_mm");
  CoverageMotion mo;
  mo.print_speed_mm_s = p.at("speed_mm_s");
  mo.travel_speed_mm_s = p.at("travel_speed_mm_s");
  mo.accel_mm_s2 = p.at("accel_mm_s2");
  double retract = mo.retract_speed_mm_s;
  if (profile.extruder.max_flow_mm3_s > 0)
    retract = std::min(retract, 0.9 * profile.extruder.max_flow_mm3_s / profile.filament_area_mm2());
  if (profile.extruder.max_velocity_mm_s > 0) retract = std::min(retract, 0.9 * profile.extruder.max_velocity_mm_s);
  mo.retract_speed_mm_s = retract;
  return {set, mo};
}

// The one-layer test pattern in the coverage planner's order (or the zigzag's), with both
// orders' statistics as comments.
void build_test_pattern(const ExperimentRequest& r, Experiment& e) {
  const machine::MachineProfile& profile = r.profile;
  auto& p = e.params;
  auto& g = e.gcode;
  const auto [set, mo] = pattern_set_and_motion(p, profile);
  const auto plan = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "zigzag" : "pce", mo);
  const auto other = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "pce" : "zigzag", mo);
  for (const auto* pl : {&plan, &other})
    g.push_back(fmt::format("; {} order: print {} mm, travel {} mm, {} retractions, estimated {} s", pl->planner,
                            num(pl->stats.print_mm, 1), num(pl->stats.travel_mm, 1), pl->stats.retractions,
                            num(pl->stats.time_s, 1)));
  const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
  print_prologue(g, p, profile, r.dialect, mo.accel_mm_s2);
  const auto& first = plan.moves.front();
  g.push_back(fmt::format("G0 X{} Y{} F{}", num(first.x0), num(first.y0), num(mo.travel_speed_mm_s * 60, 1)));
  for (const auto& m : plan.moves) {
    if (m.extrude) {
      g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(m.x1), num(m.y1),
                              num(e_per_mm * std::hypot(m.x1 - m.x0, m.y1 - m.y0), 5),
                              num(mo.print_speed_mm_s * 60, 1)));
    } else {
      g.push_back(fmt::format("G1 E-{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
      g.push_back(fmt::format("G0 X{} Y{} F{}", num(m.x1), num(m.y1), num(mo.travel_speed_mm_s * 60, 1)));
      g.push_back(fmt::format("G1 E{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
    }
  }
  g.push_back(r.dialect.wait_for_moves());
}

}  // namespace

bool build_print_experiment(const ExperimentRequest& r, Experiment& e) {
  auto& p = e.params;
  if (r.id == Protocol::ring_print) {
    build_ring_print(r, e);
  } else if (r.id == Protocol::line_steps) {
    if (std::isnan(p["center_x_mm"])) p["center_x_mm"] = mid(r.profile, "x");
    if (std::isnan(p["first_y_mm"])) p["first_y_mm"] = mid(r.profile, "y") - 50;
    append_line_steps_gcode(e.gcode, p, r.profile, r.dialect);
  } else if (r.id == Protocol::test_pattern) {
    build_test_pattern(r, e);
  } else {
    return false;
  }
  return true;
}

}  // namespace tunekit::protocols::experiment_gcode
