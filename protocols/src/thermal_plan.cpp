// The designed thermal experiment (thermal_plan.hpp) and its G-code (protocol heater-identify).
#include "tunekit/protocols/thermal_plan.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "experiment_gcode.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::protocols {

namespace {

// The plan's timeline, s after the record starts (five minutes of machine time at most). The
// heat-up is given the longest: a 25 J/K block on a 30 W cartridge rises about 1.2 K/s.
constexpr double kRestS = 5;         // at rest: the ambient and the start
constexpr double kHeatUpEndS = 120;  // heat-up and the controller's settling
constexpr double kStepDownEndS = 145;
constexpr double kStepUpEndS = 170;
constexpr double kFanEndS = 200;
constexpr double kFeedEndS = 230;  // the fitted part ends here
constexpr double kHeldFanEndS = 258;
constexpr double kHeldFeedEndS = 286;
// The default extrusion step's volumetric flow, mm^3/s, and its share of the machine's limits.
constexpr double kThermalFlowMm3S = 4.0;
constexpr double kShareOfFeedLimits = 1.0 / 3.0;
// The printing temperature must leave the step down this far above the ambient, K.
constexpr double kLowestStepFloorC = 60;
// Height above the bed the nozzle extrudes into the air at, mm (at most half the Z travel), and
// the speeds it is parked at (at most the axes' own limits), mm/s.
constexpr double kPurgeHeightMm = 30;
constexpr double kParkZSpeedMmS = 10;
constexpr double kParkXySpeedMmS = 100;

}  // namespace

double default_thermal_feed_mm_s(const machine::MachineProfile& p) {
  const double area = p.filament_area_mm2();
  double feed = kThermalFlowMm3S / area;
  if (p.extruder.max_flow_mm3_s > 0) feed = std::min(feed, kShareOfFeedLimits * p.extruder.max_flow_mm3_s / area);
  if (p.extruder.max_velocity_mm_s > 0) feed = std::min(feed, kShareOfFeedLimits * p.extruder.max_velocity_mm_s);
  return feed;
}

ThermalPlan plan_thermal_experiment(const std::map<std::string, double>& params,
                                    const machine::MachineProfile& profile) {
  const double hot = params.at("hotend_c"), down = params.at("step_down_c"), fan = params.at("fan_duty");
  const double feed = std::isnan(params.at("feed_mm_s")) ? default_thermal_feed_mm_s(profile) : params.at("feed_mm_s");
  const double max_c = profile.temperature.hotend_max_c;
  if (!(hot <= max_c))
    throw InputError(
        fmt::format("heater-identify: hotend_c {:g} degC exceeds the profile's hotend_max_c {:g} degC: "
                    "nothing above the maximum is ever commanded",
                    hot, max_c));
  if (!(hot - down >= kLowestStepFloorC))
    throw InputError(
        fmt::format("heater-identify: hotend_c {:g} degC less step_down_c {:g} K is below {:g} degC: give "
                    "a printing temperature",
                    hot, down, kLowestStepFloorC));
  if (!(fan > 0 && fan <= 1))
    throw InputError(fmt::format("heater-identify: fan_duty must be in (0, 1], not {:g}", fan));
  ThermalPlan plan;
  plan.hotend_c = hot;
  plan.pieces = {{0, 0, 0, 0, "rest", false},
                 {kRestS, hot, 0, 0, "heat-up", false},
                 {kHeatUpEndS, hot - down, 0, 0, "step down", false},
                 {kStepDownEndS, hot, 0, 0, "step up", false},
                 {kStepUpEndS, hot, fan, 0, "fan step", false},
                 {kFanEndS, hot, 0, feed, "extrusion step", false},
                 {kFeedEndS, hot, fan, 0, "held-out fan step", true},
                 {kHeldFanEndS, hot, 0, feed, "held-out extrusion step", true}};
  plan.duration_s = kHeldFeedEndS;
  plan.held_out_from_s = kFeedEndS;
  return plan;
}

namespace experiment_gcode {

namespace {

std::string fan_line(double duty) {
  return duty > 0 ? fmt::format("M106 S{}", std::lround(std::clamp(duty, 0.0, 1.0) * 255)) : std::string("M107");
}

}  // namespace

/// heater-identify: the plan as G-code. The nozzle is parked above the middle of the bed, the
/// heater and fan set at each piece's start, the time between pieces a dwell or the extrusion's
/// own moves (then M400 ends it), the heater recorded from rest to the plan's end and turned off.
void build_thermal_experiment(const ExperimentRequest& r, Experiment& e) {
  auto& p = e.params;
  if (std::isnan(p["feed_mm_s"])) p["feed_mm_s"] = default_thermal_feed_mm_s(r.profile);
  const ThermalPlan plan = plan_thermal_experiment(p, r.profile);
  auto& g = e.gcode;
  std::vector<std::string> restore;
  g.push_back("G28");
  g.push_back("G90");
  const auto& ax = r.profile.axis("x");  // a profile without the axis is refused, not indexed
  const auto& ay = r.profile.axis("y");
  const auto& az = r.profile.axis("z");
  const double z = std::min(kPurgeHeightMm, 0.5 * (az.max_mm - az.min_mm));
  const double xy_speed = std::min({kParkXySpeedMmS, ax.max_velocity_mm_s, ay.max_velocity_mm_s});
  // Z at its own acceleration, then X and Y at the print's (as the printed tests' prologue does).
  g.push_back(r.dialect.set_accel(std::min(r.profile.print.max_accel_mm_s2, az.max_accel_mm_s2)));
  g.push_back(fmt::format("G1 Z{} F{}", num(z, 3), num(60 * std::min(az.max_velocity_mm_s, kParkZSpeedMmS), 3)));
  g.push_back(r.dialect.set_accel(std::min({r.profile.print.max_accel_mm_s2, ax.max_accel_mm_s2, ay.max_accel_mm_s2})));
  g.push_back(
      fmt::format("G1 X{} Y{} F{}", num(mid(r.profile, "x"), 3), num(mid(r.profile, "y"), 3), num(60 * xy_speed, 3)));
  g.push_back("M83 ; relative extrusion");
  const FeedPlan fp =
      extruder_accel(g, restore, std::min(2000.0, r.profile.extruder.max_accel_mm_s2), r.profile, r.dialect);
  g.push_back("M107");
  g.push_back("M104 S0 ; from rest");
  g.push_back("M400");
  g.push_back(";@record heater on");
  for (std::size_t i = 0; i < plan.pieces.size(); ++i) {
    const auto& pc = plan.pieces[i];
    const double end = i + 1 < plan.pieces.size() ? plan.pieces[i + 1].from_s : plan.duration_s;
    g.push_back(fmt::format("; {} from {:g} s", pc.what, pc.from_s));
    g.push_back(fmt::format("M104 S{:.0f}", pc.target_c));
    g.push_back(fan_line(pc.fan_duty));
    if (pc.feed_mm_s > 0) {
      feed_move(g, fp, pc.feed_mm_s, end - pc.from_s);
      g.push_back("M400");
    } else {
      g.push_back(fmt::format("G4 P{}", std::lround((end - pc.from_s) * 1000)));
    }
  }
  g.push_back(";@record heater off");
  g.push_back("M104 S0 ; heater off");
  g.push_back("M107");
  epilogue(g, restore);
  record_feed_plan(e, fp);
  e.excitation["held_out_from_s"] = plan.held_out_from_s;
  e.excitation["record_s"] = plan.duration_s;
  nlohmann::json pieces = nlohmann::json::array();
  for (const auto& pc : plan.pieces)
    pieces.push_back({{"from_s", pc.from_s},
                      {"target_c", pc.target_c},
                      {"fan_duty", pc.fan_duty},
                      {"feed_mm_s", pc.feed_mm_s},
                      {"what", pc.what},
                      {"held_out", pc.held_out}});
  e.excitation["pieces"] = pieces;
}

}  // namespace experiment_gcode

}  // namespace tunekit::protocols
