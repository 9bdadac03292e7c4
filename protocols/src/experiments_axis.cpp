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
#include "sweep_moves.hpp"

namespace tunekit::protocols::experiment_gcode {

namespace {

/// Marlin's and RepRapFirmware's M201 caps the acceleration a move may ask for: raised to the
/// sweep's peak for the test, the profile's value restored after.
void raise_max_accel(double peak_accel, const machine::MachineProfile& profile, std::vector<std::string>& prologue,
                     std::vector<std::string>& restore, nlohmann::json& changed) {
  prologue.push_back(fmt::format("M201 X{0} Y{0}", num(std::floor(peak_accel), 0)));
  restore.push_back(fmt::format("M201 X{0} Y{0}", num(profile.state.max_accel_xy_mm_s2, 3)));
  changed.push_back("M201");
}

/// The sweep's test settings: everything the firmware would do differently from the labelled
/// moves is turned off for the test and restored after (the epilogue, also sent after an abort).
void sweep_test_settings(const ExperimentRequest& r, double peak_accel, std::vector<std::string>& prologue,
                         std::vector<std::string>& restore, nlohmann::json& changed) {
  const machine::MachineProfile& profile = r.profile;
  switch (r.dialect.firmware()) {
    case firmware::Firmware::klipper:
      // As Klipper's own TEST_RESONANCES (klippy/extras/resonance_tester.py, run_test):
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
      raise_max_accel(peak_accel, profile, prologue, restore, changed);
      break;
    default:
      // Marlin: moves shorter than DEFAULT_MINSEGMENTTIME (M205 B, us) are slowed
      // (planner.cpp), M204 is capped by M201 (planner.cpp limit_and_warn).
      prologue.push_back("M205 B0");
      restore.push_back(fmt::format("M205 B{}", num(profile.state.min_segment_time_s * 1e6, 0)));
      changed.push_back("M205 B");
      raise_max_accel(peak_accel, profile, prologue, restore, changed);
      break;
  }
  shaping_off(profile, r.dialect, prologue, restore, changed);
}

/// The sweep's design from the parameters: the sweeping motion is Klipper's (on by default
/// there, refused elsewhere: its moves join at speed, which only Klipper's planner was checked for).
SweepDesign sweep_design(const ExperimentRequest& r, std::map<std::string, double>& p) {
  const bool klipper = r.dialect.firmware() == firmware::Firmware::klipper;
  SweepDesign d = sweep_design_from_params(p, r.profile.axis(r.axis_in).max_accel_mm_s2);
  if (d.sweeping() && !klipper)
    throw InputError(fmt::format(
        "axis-sweep's sweeping motion (sweeping_accel {:g} mm/s^2) follows Klipper's TEST_RESONANCES and is made "
        "for Klipper's planner only; on {} give -p sweeping_accel=0",
        d.sweeping_accel_mm_s2, firmware::to_string(r.dialect.firmware())));
  if (!(d.pulse_accel_cap() > 0))
    throw InputError(fmt::format(
        "axis-sweep's sweeping motion (sweeping_accel {:g} mm/s^2) leaves the pulses no acceleration under the {} "
        "axis' limit {:g} mm/s^2: give a lower sweeping_accel",
        d.sweeping_accel_mm_s2, r.axis_in, d.max_accel_mm_s2));
  if (r.dialect.firmware() == firmware::Firmware::marlin || r.dialect.firmware() == firmware::Firmware::prusa) {
    // Marlin joins a move with fewer than MIN_STEPS_PER_SEGMENT steps with the next one
    // (planner.cpp _buffer_steps; Configuration_adv.h MIN_STEPS_PER_SEGMENT 6).
    const double spm = r.axis_in == "x" ? r.profile.state.steps_per_mm_x : r.profile.state.steps_per_mm_y;
    d.min_half_mm = firmware::limits::kMarlinMinStepsPerSegment / spm;
  }
  return d;
}

/// The sweep's moves as G-code from `center` along axis letter `A`; returns the farthest
/// excursions from the centre (mm, below and above).
std::pair<double, double> emit_sweep(const ExperimentRequest& r, const std::vector<SweepMove>& moves,
                                     const std::string& A, double center, std::vector<std::string>& g) {
  const bool klipper = r.dialect.firmware() == firmware::Firmware::klipper;
  double pos = center, lo = 0, hi = 0, accel = -1;
  for (const auto& m : moves) {
    if (m.dwell_s > 0) {
      g.push_back(fmt::format("G4 P{}", num(m.dwell_s * 1000, 3)));
      continue;
    }
    if (m.accel_mm_s2 > 0 && m.accel_mm_s2 != accel) {
      accel = m.accel_mm_s2;
      // Klipper takes a fractional ACCEL: the sweeping motion leaves accelerations of a few mm/s^2.
      g.push_back(klipper ? fmt::format("SET_VELOCITY_LIMIT ACCEL={}", num(accel, 3)) : r.dialect.set_accel(accel));
    }
    pos += m.dist_mm;
    lo = std::min(lo, pos - center);
    hi = std::max(hi, pos - center);
    g.push_back(fmt::format("G1 {}{} F{}", A, num(pos, 5), num(m.feed_mm_s * 60, 3)));
    if (m.stop_after) g.push_back("G4 P0");
    guard_line_count(g, r.limits, r.protocol);
  }
  return {lo, hi};
}

/// Bed slinger: the mass placed on the bed for the sweep, and where (the middle of the travel
/// unless given), in the experiment's record and as a comment at the top of its G-code.
void record_bed_load(const ExperimentRequest& r, Experiment& e) {
  auto& p = e.params;
  if (std::isnan(p["load_x_mm"])) p["load_x_mm"] = mid(r.profile, "x");
  if (std::isnan(p["load_y_mm"])) p["load_y_mm"] = mid(r.profile, "y");
  if (!(p.at("load_kg") > 0)) return;
  const std::string place = fmt::format("place {} kg on the bed, centred at X{} Y{} (mm), fixed so it cannot slide",
                                        num(p.at("load_kg"), 3), num(p.at("load_x_mm"), 1), num(p.at("load_y_mm"), 1));
  e.excitation["bed_load"] = {
      {"load_kg", p.at("load_kg")}, {"x_mm", p.at("load_x_mm")}, {"y_mm", p.at("load_y_mm")}, {"instruction", place}};
  e.gcode.push_back("; bed load: " + place);
}

void build_axis_sweep(const ExperimentRequest& r, Experiment& e) {
  const std::string& axis_in = r.axis_in;
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  auto& p = e.params;
  auto& g = e.gcode;
  if (axis_in != "x" && axis_in != "y")
    throw InputError(fmt::format("axis-sweep needs --axis x or y, not '{}'", axis_in));
  e.axis = axis_in;
  const std::string other = axis_in == "x" ? "y" : "x";
  if (std::isnan(p["center_mm"])) p["center_mm"] = mid(profile, axis_in);
  if (std::isnan(p["other_mm"])) p["other_mm"] = mid(profile, other);
  record_bed_load(r, e);
  const SweepDesign design = sweep_design(r, p);
  const double f0 = design.freq_start_hz, f1 = design.freq_end_hz, rate = design.hz_per_sec;
  if (f1 <= f0) throw InputError("freq_end_hz must exceed freq_start_hz");
  // Half periods of the sweep: the integral of 2 f dt = 2 f df / rate from f0 to f1; two lines
  // each, about five with the sweeping motion (two moves and their accelerations, a held
  // slowest point).
  check_plan(r.protocol, (design.sweeping() ? 5.5 : 2.0) * (f1 * f1 - f0 * f0) / rate + 12,
             (f1 - f0) / rate + 2 * p.at("settle_s"), r.limits);
  const std::string A = axis_in == "x" ? "X" : "Y", O = axis_in == "x" ? "Y" : "X";
  const double axis_max_accel = profile.axis(axis_in).max_accel_mm_s2;
  const double travel_accel = std::min(3000.0, axis_max_accel);
  const auto pulses = vibration_pulses(design);
  // The pulses' own time (a first half period 1/(2 f0) can be far longer than the rate says) and
  // the sweeping motion's switches, two more moves each, within the caps before they are made.
  const double pulses_s = pulses.empty() ? 0.0 : pulses.back().t_end_s;
  check_plan(r.protocol, design.sweeping() ? 4 * pulses_s / (design.sweeping_period_s / 2) : 0.0,
             pulses_s + 2 * p.at("settle_s"), r.limits);
  const auto segments = add_sweeping(pulses, design);
  // Klipper ends a sweep that is still moving at the acceleration it restores (run_test).
  const auto moves = sweep_moves(segments, std::min(travel_accel, accel_to_restore(profile)));
  double peak_accel = 0, peak_speed = 0, sweep_s = 0;
  for (const auto& m : moves) {
    peak_accel = std::max(peak_accel, m.accel_mm_s2);
    peak_speed = std::max(peak_speed, m.feed_mm_s);
    sweep_s += m.duration_s;
  }
  std::vector<std::string> prologue, restore;
  nlohmann::json changed = nlohmann::json::array();
  sweep_test_settings(r, peak_accel, prologue, restore, changed);
  e.excitation["test_settings"] = prologue;
  e.excitation["changed"] = changed;
  e.excitation["peak_accel_mm_s2"] = peak_accel;
  e.excitation["accel_held_above_hz"] = design.held_above_hz();
  e.excitation["accel_limit_mm_s2"] = design.max_accel_mm_s2;
  e.excitation["peak_speed_mm_s"] = peak_speed;
  e.excitation["sweep_duration_s"] = sweep_s;  // the moves as planned, without the settle dwells
  if (design.min_half_mm > 0) e.excitation["min_move_mm"] = design.min_half_mm;
  g.push_back("G28");
  g.push_back("G90");
  g.push_back(d.set_accel(travel_accel));
  g.push_back(fmt::format("G1 {}{} {}{} F{}", A, num(p["center_mm"]), O, num(p["other_mm"]),
                          num(p.at("travel_speed_mm_s") * 60, 1)));
  g.push_back(d.wait_for_moves());
  g.insert(g.end(), prologue.begin(), prologue.end());
  g.push_back(";@record accelerometer on");
  g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
  const auto [lo, hi] = emit_sweep(r, moves, A, p["center_mm"], g);
  e.excitation["excursion_mm"] = {lo, hi};
  if (design.sweeping()) e.excitation["sweeping_excursion_mm"] = sweeping_excursion_mm(design);
  g.push_back(fmt::format("G4 P{}", std::lround(p["settle_s"] * 1000)));
  g.push_back(d.wait_for_moves());
  g.push_back(";@record accelerometer off");
  epilogue(g, restore);
}

// The axis-rectangle test: the corners at the move's speed and acceleration with a pause at each,
// recorded by the accelerometer with the firmware's shaping off.
void build_axis_rectangle(const ExperimentRequest& r, Experiment& e) {
  const machine::MachineProfile& profile = r.profile;
  const firmware::Dialect& d = r.dialect;
  auto& p = e.params;
  auto& g = e.gcode;
  const double w = p.at("width_mm"), h = p.at("height_mm"), v = p.at("speed_mm_s");
  const int reps = static_cast<int>(p.at("repeats"));
  check_plan(r.protocol, 8.0 * reps + 12, (reps * 4 + 1) * p.at("pause_s") + reps * 2 * (w + h) / v, r.limits);
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
  for (int rep = 0; rep < reps; ++rep) {
    for (const auto& corner :
         {std::pair{x0 + w, y0}, std::pair{x0 + w, y0 + h}, std::pair{x0, y0 + h}, std::pair{x0, y0}}) {
      g.push_back(fmt::format("G1 X{} Y{} F{}", num(corner.first), num(corner.second), num(v * 60, 1)));
      g.push_back(fmt::format("G4 P{}", pause_ms));
    }
  }
  g.push_back(d.wait_for_moves());
  g.push_back(";@record accelerometer off");
  epilogue(g, restore);
}

}  // namespace

bool build_axis_experiment(const ExperimentRequest& r, Experiment& e) {
  if (r.id == Protocol::axis_sweep) {
    build_axis_sweep(r, e);
  } else if (r.id == Protocol::axis_rectangle) {
    build_axis_rectangle(r, e);
  } else {
    return false;
  }
  return true;
}

}  // namespace tunekit::protocols::experiment_gcode
