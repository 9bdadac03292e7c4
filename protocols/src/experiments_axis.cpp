// The axis protocols: a frequency sweep of one axis (axis-sweep) and a rectangle with pauses at
// its corners (axis-rectangle), with the accelerometer recording and the firmware's test settings.
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

bool build_axis_experiment(const ExperimentRequest& r, Experiment& e) {
  const std::string& protocol = r.protocol;
  const std::string& axis_in = r.axis_in;
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  const ProtocolLimits& limits = r.limits;
  auto& p = e.params;
  auto& g = e.gcode;
  auto guard = [&] { guard_line_count(g, r.limits, r.protocol); };
  if (protocol == "axis-sweep") {
    if (axis_in != "x" && axis_in != "y")
      throw InputError(fmt::format("axis-sweep needs --axis x or y, not '{}'", axis_in));
    e.axis = axis_in;
    const std::string other = axis_in == "x" ? "y" : "x";
    if (std::isnan(p["center_mm"])) p["center_mm"] = mid(profile, axis_in);
    if (std::isnan(p["other_mm"])) p["other_mm"] = mid(profile, other);
    const double f0 = p.at("freq_start_hz"), f1 = p.at("freq_end_hz"), rate = p.at("hz_per_sec");
    const double aph = p.at("accel_per_hz");
    if (f1 <= f0) throw InputError("freq_end_hz must exceed freq_start_hz");
    // Half-periods of the sweep: the integral of 2 f dt = 2 f df / rate from f0 to f1; two lines each.
    check_plan(protocol, 2 * (f1 * f1 - f0 * f0) / rate + 12, (f1 - f0) / rate + 2 * p.at("settle_s"), limits);
    const std::string A = axis_in == "x" ? "X" : "Y", O = axis_in == "x" ? "Y" : "X";
    const double axis_max_accel = profile.axis(axis_in).max_accel_mm_s2;
    // The sweep's moves, designed within the firmware's planner rules.
    struct SweepMove {
      double accel, dist, vpk;
    };
    std::vector<SweepMove> moves;
    double min_len = 0;
    if (d.firmware() == firmware::Firmware::marlin || d.firmware() == firmware::Firmware::prusa) {
      // Marlin joins a move with fewer than MIN_STEPS_PER_SEGMENT steps with the next one
      // (planner.cpp _buffer_steps; Configuration_adv.h MIN_STEPS_PER_SEGMENT 6).
      const double spm = axis_in == "x" ? profile.state.steps_per_mm_x : profile.state.steps_per_mm_y;
      min_len = firmware::limits::kMarlinMinStepsPerSegment / spm;
    }
    {
      double t = 0, f = f0;
      while (f < f1) {
        const double th = 1.0 / (2 * f);
        double a = aph * f;
        // A triangle of duration th at acceleration a covers a th^2 / 4.
        if (a * th * th / 4 < 1.5 * min_len) a = 1.5 * min_len * 4 / (th * th);
        if (a > axis_max_accel)
          throw InputError(fmt::format(
              "axis-sweep at {:.1f} Hz on Marlin: a half period must move at least {} steps (MIN_STEPS_PER_SEGMENT, "
              "Configuration_adv.h) = {:.4g} mm, which needs {:.0f} mm/s^2, above the axis limit {:.0f} mm/s^2; lower "
              "freq_end_hz or raise [firmware_state] steps_per_mm",
              f, firmware::limits::kMarlinMinStepsPerSegment, min_len, a, axis_max_accel));
        moves.push_back({a, a * th * th / 4, a * th / 2});
        t += th;
        f = f0 + rate * t;
      }
    }
    double peak_accel = 0;
    for (const auto& m : moves) peak_accel = std::max(peak_accel, m.accel);
    // Test settings: everything the firmware would do differently from the labelled moves is
    // turned off for the test and restored after (the epilogue, also sent after an abort).
    std::vector<std::string> prologue, restore;
    nlohmann::json changed = nlohmann::json::array();
    switch (d.firmware()) {
      case firmware::Firmware::klipper:
        // As Klipper's own TEST_RESONANCES (klippy/extras/resonance_tester.py:194-199):
        // MINIMUM_CRUISE_RATIO=0 and input shaping off.
        prologue.push_back("SET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO=0");
        restore.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={} MINIMUM_CRUISE_RATIO={}",
                                      num(accel_to_restore(profile), 0), num(profile.state.minimum_cruise_ratio, 3)));
        changed.push_back("minimum_cruise_ratio");
        break;
      case firmware::Firmware::reprapfirmware:
        // RRF joins a reversal at M566/2 (DDA.cpp MatchSpeeds, totalFraction 2): the lowest jerk
        // it accepts (Configuration.h MinimumJerk 0.1 mm/s) makes every half period rest to rest.
        prologue.push_back("M566 X6 Y6");
        restore.push_back(fmt::format("M566 X{} Y{}", num(profile.state.jerk_xy_mm_s * 60, 1),
                                      num(profile.state.jerk_xy_mm_s * 60, 1)));
        changed.push_back("M566");
        prologue.push_back(fmt::format("M201 X{} Y{}", num(peak_accel, 0), num(peak_accel, 0)));
        restore.push_back(fmt::format("M201 X{} Y{}", num(profile.state.max_accel_xy_mm_s2, 0),
                                      num(profile.state.max_accel_xy_mm_s2, 0)));
        changed.push_back("M201");
        break;
      default:
        // Marlin: moves shorter than DEFAULT_MINSEGMENTTIME (M205 B, us) are slowed
        // (planner.cpp), M204 is capped by M201 (planner.cpp limit_and_warn).
        prologue.push_back("M205 B0");
        restore.push_back(fmt::format("M205 B{}", num(profile.state.min_segment_time_s * 1e6, 0)));
        changed.push_back("M205 B");
        prologue.push_back(fmt::format("M201 X{} Y{}", num(peak_accel, 0), num(peak_accel, 0)));
        restore.push_back(fmt::format("M201 X{} Y{}", num(profile.state.max_accel_xy_mm_s2, 0),
                                      num(profile.state.max_accel_xy_mm_s2, 0)));
        changed.push_back("M201");
        break;
    }
    shaping_off(profile, d, prologue, restore, changed);
    e.excitation["test_settings"] = prologue;
    e.excitation["changed"] = changed;
    e.excitation["peak_accel_mm_s2"] = peak_accel;
    if (min_len > 0) e.excitation["min_move_mm"] = min_len;
    g.push_back("G28");
    g.push_back("G90");
    g.push_back(d.set_accel(std::min(3000.0, axis_max_accel)));
    g.push_back(fmt::format("G1 {}{} {}{} F{}", A, num(p["center_mm"]), O, num(p["other_mm"]),
                            num(p.at("travel_speed_mm_s") * 60, 1)));
    g.push_back(d.wait_for_moves());
    g.insert(g.end(), prologue.begin(), prologue.end());
    g.push_back(";@record accelerometer on");
    g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
    double pos = p["center_mm"];
    int sign = 1;
    for (const auto& m : moves) {
      g.push_back(d.set_accel(m.accel));
      pos += sign * m.dist;
      g.push_back(fmt::format("G1 {}{} F{}", A, num(pos, 5), num(m.vpk * 60, 3)));
      guard();
      sign = -sign;
    }
    g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer off");
    epilogue(g, restore);
  } else if (protocol == "axis-rectangle") {
    const double w = p.at("width_mm"), h = p.at("height_mm"), v = p.at("speed_mm_s");
    const int reps = static_cast<int>(p.at("repeats"));
    check_plan(protocol, 8.0 * reps + 12, (reps * 4 + 1) * p.at("pause_s") + reps * 2 * (w + h) / v, limits);
    const long pause_ms = std::lround(p.at("pause_s") * 1000);
    const double x0 = mid(profile, "x") - w / 2, y0 = mid(profile, "y") - h / 2;
    const double accel = p.at("accel_mm_s2");
    std::vector<std::string> prologue, restore;
    nlohmann::json changed = nlohmann::json::array();
    g.push_back("G28");
    g.push_back("G90");
    if (d.firmware() != firmware::Firmware::klipper && accel > profile.state.max_accel_xy_mm_s2) {
      // Marlin and RepRapFirmware cap M204 by M201 (Marlin planner.cpp limit_and_warn, RRF
      // DDA.cpp): the rectangle's acceleration is allowed for the test and restored after.
      g.push_back(fmt::format("M201 X{} Y{}", num(accel, 0), num(accel, 0)));
      restore.push_back(fmt::format("M201 X{} Y{}", num(profile.state.max_accel_xy_mm_s2, 0),
                                    num(profile.state.max_accel_xy_mm_s2, 0)));
      changed.push_back("M201");
    }
    g.push_back(d.set_accel(accel));
    g.push_back(fmt::format("G1 X{} Y{} F{}", num(x0), num(y0), num(v * 60, 1)));
    g.push_back(d.wait_for_moves());
    // The overshoot is measured without the firmware's input shaping (restored after).
    shaping_off(profile, d, prologue, restore, changed);
    g.insert(g.end(), prologue.begin(), prologue.end());
    e.excitation["test_settings"] = prologue;
    e.excitation["changed"] = changed;
    g.push_back(";@record accelerometer on");
    g.push_back(fmt::format("G4 P{}", pause_ms));
    for (int r = 0; r < reps; ++r) {
      for (const auto& corner :
           {std::pair{x0 + w, y0}, std::pair{x0 + w, y0 + h}, std::pair{x0, y0 + h}, std::pair{x0, y0}}) {
        g.push_back(fmt::format("G1 X{} Y{} F{}", num(corner.first), num(corner.second), num(v * 60, 1)));
        g.push_back(fmt::format("G4 P{}", pause_ms));
      }
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer off");
    epilogue(g, restore);
  } else {
    return false;
  }
  return true;
}

}  // namespace tunekit::protocols::experiment_gcode
