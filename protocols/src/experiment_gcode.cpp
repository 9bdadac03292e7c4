// The protocols' shared G-code helpers: number formatting, extrude-only feeds as each firmware
// plans them, the restore epilogue, input shaping off for a test, and the plan caps.
#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/trajectory.hpp"

#include "experiment_gcode.hpp"

namespace tunekit::protocols::experiment_gcode {

double mid(const machine::MachineProfile& p, const std::string& axis) {
  const auto& a = p.axis(axis);
  return 0.5 * (a.min_mm + a.max_mm);
}

std::string num(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

constexpr double kMaxMovesPerSegment = 1e6;

/// One constant-feed segment of `duration_s` at `feed_mm_s`, split into moves of at most
/// max_len_mm. When the firmware stops after each move, the move's speed is raised so that the
/// move with its ramps (d / v + v / a) still takes its share of the duration and delivers its
/// share of the length: the staircase keeps its labelled timing.
void feed_move(std::vector<std::string>& g, const FeedPlan& fp, double feed_mm_s, double duration_s) {
  const double total = feed_mm_s * duration_s;
  const double moves = std::ceil(total / fp.max_len_mm - 1e-9);
  // A segment is at most a million moves (the most lines any protocol may have); NaN fails too.
  if (!(moves <= kMaxMovesPerSegment))
    throw InputError(fmt::format(
        "a feed segment of {:.4g} mm ({:.4g} mm/s for {:.4g} s) would take more than {:.0f} extrude-only moves of at "
        "most {:.4g} mm (the extruder's max_extrude_only_distance): shorten the segment or lower the feed",
        total, feed_mm_s, duration_s, kMaxMovesPerSegment, fp.max_len_mm));
  const int n = std::max(1, static_cast<int>(moves));
  const double d = total / n, dt = duration_s / n;
  double v = feed_mm_s;
  if (fp.stops) {
    const double a = fp.accel_mm_s2;
    const double disc = a * a * dt * dt - 4 * a * d;
    if (disc < 0)
      throw InputError(fmt::format(
          "a {:.4g} s feed segment of {:.4g} mm cannot keep its timing on a firmware that stops after every "
          "extrude-only move (Klipper) at {:.0f} mm/s^2: it needs at least {:.0f} mm/s^2 (4 d / t^2) or a longer "
          "segment",
          dt, d, a, 4 * d / (dt * dt)));
    v = 0.5 * (a * dt - std::sqrt(disc));
  }
  for (int i = 0; i < n; ++i) g.push_back(fmt::format("G1 E{} F{}", num(d, 5), num(v * 60, 3)));
}

/// The acceleration commands for extrude-only moves, per firmware, and their restore lines:
/// Klipper caps them by SET_VELOCITY_LIMIT ACCEL and max_extrude_only_accel (extruder.py
/// check_move); Marlin plans moves without X/Y/Z steps with the retract acceleration M204 R
/// (planner.cpp); RepRapFirmware applies M204 to XY moves only (DDA.cpp "apply M204
/// acceleration limits to XY moves"), so M201 E limits them.
FeedPlan extruder_accel(std::vector<std::string>& g, std::vector<std::string>& restore, double a,
                        const machine::MachineProfile& profile, const firmware::Dialect& d) {
  FeedPlan fp;
  fp.max_len_mm = profile.extruder.max_extrude_only_distance_mm;
  // Whole mm/s^2 rounded down (never above what was checked); the machine's own values restored
  // as its configuration has them.
  a = std::floor(a);
  switch (d.firmware()) {
    case firmware::Firmware::klipper:
      g.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={}", num(a, 0)));
      restore.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={}", num(accel_to_restore(profile), 3)));
      fp.stops = true;
      fp.accel_mm_s2 = std::min(a, profile.extruder.max_accel_mm_s2);
      break;
    case firmware::Firmware::reprapfirmware:
      g.push_back(fmt::format("M201 E{}", num(a, 0)));
      restore.push_back(fmt::format("M201 E{}", num(profile.state.max_accel_e_mm_s2, 3)));
      fp.accel_mm_s2 = a;
      break;
    default:
      // Marlin caps M204 R by the extruder's M201 E (planner.cpp: every axis' max acceleration).
      g.push_back(fmt::format("M204 R{}", num(a, 0)));
      restore.push_back(fmt::format("M204 R{}", num(profile.state.retract_accel_mm_s2, 3)));
      fp.accel_mm_s2 = std::min(a, profile.state.max_accel_e_mm_s2);
      break;
  }
  return fp;
}

FeedPlan liquefier_prologue(std::vector<std::string>& g, std::vector<std::string>& restore,
                            const std::map<std::string, double>& p, const machine::MachineProfile& profile,
                            const firmware::Dialect& d) {
  g.push_back("M83 ; relative extrusion");
  if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
  return extruder_accel(g, restore, p.at("accel_mm_s2"), profile, d);
}

/// Appends the restore lines after the ";@epilogue" marker: the runner also sends them after
/// an abort (after stopping motion).
void epilogue(std::vector<std::string>& g, const std::vector<std::string>& restore) {
  if (restore.empty()) return;
  g.push_back(";@epilogue");
  g.insert(g.end(), restore.begin(), restore.end());
}

/// "type:freq:zeta" of the profile's [firmware_state].
struct StateShaper {
  std::string type;
  std::string freq, zeta;
};
StateShaper split_state_shaper(const std::string& v) {
  StateShaper s;
  const auto a = v.find(':'), b = v.rfind(':');
  s.type = v.substr(0, a);
  s.freq = v.substr(a + 1, b - a - 1);
  s.zeta = v.substr(b + 1);
  return s;
}

/// Input shaping off for a test and its restore lines, per firmware, when the profile says the
/// machine has shaping configured ([firmware_state] shaper_x/y): Klipper as its resonance tester
/// (SET_INPUT_SHAPER with zero frequencies), Marlin M593 F0 (M593.cpp: without X/Y every shaped
/// axis), RepRapFirmware M593 P"none". A Marlin running fixed-time motion with a shaper (its M493
/// report, in the dialect) bypasses M593 (stepper.cpp isr()): its FT_MOTION shapers are turned
/// off and set back instead, in the M493 letters of the form its report took (marlin_m493.hpp).
void shaping_off(const machine::MachineProfile& profile, const firmware::Dialect& d, std::vector<std::string>& prologue,
                 std::vector<std::string>& restore, nlohmann::json& changed) {
  if (d.firmware() == firmware::Firmware::marlin && d.ft_motion().shaping()) {
    const auto off = firmware::m493_shaping_off(d.ft_motion());
    const auto back = firmware::m493_shaping_restore(d.ft_motion());
    prologue.insert(prologue.end(), off.begin(), off.end());
    restore.insert(restore.end(), back.begin(), back.end());
    changed.push_back("M493");
    return;
  }
  const auto& shaper = profile.state.shaper;
  if (shaper.empty()) return;
  switch (d.firmware()) {
    case firmware::Firmware::klipper: {
      prologue.push_back("SET_INPUT_SHAPER SHAPER_FREQ_X=0 SHAPER_FREQ_Y=0");
      std::string r = "SET_INPUT_SHAPER";
      for (const auto& [ax, v] : shaper) {
        const auto sv = split_state_shaper(v);
        const std::string U = ax == "x" ? "X" : "Y";
        // The type as Klipper reported it, parameters and all ("mzv(n=4,t=0.9)", klippy/extras/
        // shaper_defs.py init_shaper, Klipper 2026), quoted only where Klipper's parser needs it.
        r += fmt::format(" SHAPER_TYPE_{}={} SHAPER_FREQ_{}={} DAMPING_RATIO_{}={}", U,
                         firmware::klipper_param_value(sv.type), U, sv.freq, U, sv.zeta);
      }
      restore.push_back(r);
      changed.push_back("input_shaper");
      break;
    }
    case firmware::Firmware::reprapfirmware: {
      prologue.push_back("M593 P\"none\"");
      const auto sv = split_state_shaper(shaper.begin()->second);
      restore.push_back(fmt::format("M593 P\"{}\" F{} S{}", sv.type, sv.freq, sv.zeta));
      changed.push_back("M593");
      break;
    }
    default:
      prologue.push_back("M593 F0");
      for (const auto& [ax, v] : shaper) {
        const auto sv = split_state_shaper(v);
        restore.push_back(fmt::format("M593 {} F{} D{}", ax == "x" ? "X" : "Y", sv.freq, sv.zeta));
      }
      changed.push_back("M593");
      break;
  }
}

/// Records how the staircase is timed on this firmware (the analysis uses the recorded feed).
void record_feed_plan(Experiment& e, const FeedPlan& fp) {
  e.excitation["extrude_only_moves_stop"] = fp.stops;
  e.excitation["extrude_only_accel_mm_s2"] = fp.accel_mm_s2;
  e.excitation["max_extrude_only_distance_mm"] = fp.max_len_mm;
  e.excitation["timing"] = fp.stops ? "each move's speed raised so that with its stop it takes its labelled time"
                                    : "consecutive extrude-only moves blend: the labelled timing";
}

/// Refuses a plan (lines and machine time worked out from the parameters) beyond the caps.
void check_plan(const std::string& protocol, double lines, double duration_s, const ProtocolLimits& limits) {
  if (!(duration_s <= limits.max_duration_s)) {
    const std::string how_long = std::isfinite(duration_s)
                                     ? fmt::format("{:.4g} s ({:.3g} h)", duration_s, duration_s / 3600)
                                     : std::string("an unbounded time");
    throw InputError(
        fmt::format("{} would take {} of machine time; the limit is {:g} s (change the parameters, or "
                    "raise it with --max-duration)",
                    protocol, how_long, limits.max_duration_s));
  }
  if (!(lines <= static_cast<double>(limits.max_lines)))
    throw InputError(
        fmt::format("{} would need {:.4g} G-code lines; the limit is {} (change the parameters, or "
                    "raise it with --max-lines)",
                    protocol, lines, limits.max_lines));
}

/// A second bound while generating, whatever the plan said: the memory a protocol takes stays
/// bounded even if a plan were wrong.
void guard_line_count(const std::vector<std::string>& g, const ProtocolLimits& limits, const std::string& protocol) {
  if (g.size() > limits.max_lines + 64)
    throw InputError(
        fmt::format("{} exceeds {} G-code lines while being generated (--max-lines)", protocol, limits.max_lines));
}

}  // namespace tunekit::protocols::experiment_gcode
