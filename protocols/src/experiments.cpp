#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/protocols/firmware_limits.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/protocols/gcode.hpp"
#include "tunekit/protocols/trajectory.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kMachineDefault = std::numeric_limits<double>::quiet_NaN();

// Plausibility caps of the parameters (ProtocolParam::max_value). They are far above anything
// an experiment on an FFF printer asks for and far below where the protocol arithmetic (and its
// conversion of counts and milliseconds to whole numbers) could overflow; the machine's own
// limits are checked on the generated G-code by the safety gate.
constexpr double kMaxFeedMmS = 1000;        // filament feed, mm/s
constexpr double kMaxSpeedMmS = 10000;      // toolhead speed, mm/s
constexpr double kMaxAccelMmS2 = 1e6;       // mm/s^2
constexpr double kMaxTimeS = 3600;          // one settle/hold/pause time, s
constexpr double kMaxFreqHz = 1000;         // excitation frequency, Hz
constexpr double kMaxLengthMm = 10000;      // sizes and positions, mm
constexpr double kMaxTemperatureC = 500;    // set temperature, degC (the profile's hotend_max_c applies too)
constexpr double kMaxFlowMm3S = 1000;       // volumetric flow, mm^3/s


std::vector<ProtocolSpec> make_specs() {
  const ProtocolParam hotend{"hotend_c", 210, "degC", "hot-end temperature set (and waited for) first; 0 leaves the heater alone",
                             ParamDomain::non_negative, kMaxTemperatureC};
  std::vector<ProtocolSpec> s;
  s.push_back({"liquefier-step",
               "extrusion-rate steps (low, then high/low cycles) with the load cell recording the filament force",
               {{"feed_low_mm_s", 1.0, "mm/s", "filament feed before and between steps", ParamDomain::positive, kMaxFeedMmS},
                {"feed_high_mm_s", 3.0, "mm/s", "filament feed during a step", ParamDomain::positive, kMaxFeedMmS},
                {"settle_s", 3.0, "s", "time at the low feed before the first step", ParamDomain::positive, kMaxTimeS},
                {"hold_s", 3.0, "s", "time at each level (several tau)", ParamDomain::positive, kMaxTimeS},
                {"cycles", 2, "", "number of low -> high -> low cycles", ParamDomain::count, 1000},
                {"accel_mm_s2", 2000, "mm/s^2", "filament acceleration of the feed changes", ParamDomain::positive, kMaxAccelMmS2},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"liquefier-flow-sweep",
               "feed steps up and down through flow levels spread over the hot end's range (each level reached "
               "from below and from above), load cell recorded; tau, K, theta per level and their trend with flow",
               {{"levels", 6, "", "measured flow levels, spaced geometrically between the turning flows", ParamDomain::count, 16},
                {"flow_min_mm3_s", kMachineDefault, "mm^3/s",
                 "lower turning flow, where the sweep starts and ends (default: flow_max_mm3_s / 10)", ParamDomain::positive,
                 kMaxFlowMm3S},
                {"flow_max_mm3_s", kMachineDefault, "mm^3/s",
                 "upper turning flow (default: 90 % of the profile's max_flow_mm3_s, or of max_velocity_mm_s times "
                 "the filament area when lower)",
                 ParamDomain::positive, kMaxFlowMm3S},
                {"expected_tau_s", 0.5, "s", "time constant expected at the lowest flow (the slowest)", ParamDomain::positive,
                 kMaxTimeS},
                {"hold_taus", 6, "", "time at each level in expected time constants", ParamDomain::positive, 1000},
                {"settle_s", 3.0, "s", "time at the lowest flow before the first step", ParamDomain::positive, kMaxTimeS},
                {"cycles", 1, "", "up-and-down sweeps", ParamDomain::count, 100},
                {"accel_mm_s2", 2000, "mm/s^2", "filament acceleration of the feed changes", ParamDomain::positive, kMaxAccelMmS2},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"liquefier-sine",
               "sine-dwell list: the feed oscillates around a mean at log-spaced frequencies, load cell recorded",
               {{"feed_mean_mm_s", 2.0, "mm/s", "mean filament feed", ParamDomain::positive, kMaxFeedMmS},
                {"amplitude_mm_s", 1.0, "mm/s", "feed oscillation amplitude (below the mean)", ParamDomain::non_negative, kMaxFeedMmS},
                {"freq_min_hz", 0.2, "Hz", "lowest frequency", ParamDomain::positive, kMaxFreqHz},
                {"freq_max_hz", 2.0, "Hz", "highest frequency", ParamDomain::positive, kMaxFreqHz},
                {"freq_count", 5, "", "number of frequencies (log-spaced)", ParamDomain::count, 1000},
                {"periods", 4, "", "periods per frequency", ParamDomain::positive, 10000},
                {"segment_s", 0.02, "s", "duration of one constant-feed move of the staircase", ParamDomain::positive, 10},
                {"accel_mm_s2", 3000, "mm/s^2", "filament acceleration between segments", ParamDomain::positive, kMaxAccelMmS2},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"liquefier-chirp",
               "linear chirp of the feed from freq_min_hz to freq_max_hz, load cell recorded",
               {{"feed_mean_mm_s", 2.0, "mm/s", "mean filament feed", ParamDomain::positive, kMaxFeedMmS},
                {"amplitude_mm_s", 1.0, "mm/s", "feed oscillation amplitude (below the mean)", ParamDomain::non_negative, kMaxFeedMmS},
                {"freq_min_hz", 0.1, "Hz", "start frequency", ParamDomain::positive, kMaxFreqHz},
                {"freq_max_hz", 3.0, "Hz", "end frequency", ParamDomain::positive, kMaxFreqHz},
                {"duration_s", 20, "s", "chirp duration", ParamDomain::positive, kMaxTimeS},
                {"settle_s", 2.0, "s", "steady feed at the mean before the chirp", ParamDomain::positive, kMaxTimeS},
                {"expected_tau_s", 0, "s",
                 "expected liquefier time constant (0: none); when given, the frequency range, duration and settle "
                 "time not set explicitly are sized from its corner 1/(2 pi tau)",
                 ParamDomain::non_negative, kMaxTimeS},
                {"segment_s", 0.02, "s", "duration of one constant-feed move of the staircase", ParamDomain::positive, 10},
                {"accel_mm_s2", 3000, "mm/s^2", "filament acceleration between segments", ParamDomain::positive, kMaxAccelMmS2},
                hotend},
               {"load_cell"},
               false});
  s.push_back({"ring-print",
               "Holtrup's frequency test (Tuning liquefier dynamics, MSc thesis, University of Twente, 2019): a ring "
               "printed at constant speed with the extrusion modulated by (1 + amplitude sin(periods theta)); "
               "f = periods v / (2 pi R). Measure the width with 'tunekit linewidth'",
               {{"radius_mm", 30, "mm", "ring radius R (Holtrup 2019, appendix D: 30 mm)", ParamDomain::positive, kMaxLengthMm},
                {"center_x_mm", kMachineDefault, "mm", "ring centre x (default: middle of the travel)", ParamDomain::any, kMaxLengthMm},
                {"center_y_mm", kMachineDefault, "mm", "ring centre y (default: middle of the travel)", ParamDomain::any, kMaxLengthMm},
                {"speed_mm_s", 20, "mm/s", "print speed v", ParamDomain::positive, kMaxSpeedMmS},
                {"periods", 8, "", "sine periods N around the ring", ParamDomain::count, 10000},
                {"amplitude", 0.2, "", "relative extrusion modulation A (below 1, so the extrusion stays positive)",
                 ParamDomain::non_negative, 1},
                {"segments", 360, "", "straight segments per ring (at least 12)", ParamDomain::count, 100000},
                {"z_mm", 0.2, "mm", "layer height / nozzle height of the ring", ParamDomain::positive, kMaxLengthMm},
                {"accel_mm_s2", 1000, "mm/s^2", "print acceleration", ParamDomain::positive, kMaxAccelMmS2},
                hotend},
               {},
               false});
  s.push_back({"line-steps",
               "the camera path's line test: straight lines along +X whose flow steps low -> high -> low part-way; "
               "photographed, the width along each line is the liquefier's step response (t = s / v)",
               {{"speed_mm_s", 20, "mm/s", "print speed v"},
                {"lines", 3, "", "number of lines (printed one below the other)", ParamDomain::count, 100},
                {"lead_mm", 45, "mm", "length at the low flow before the step (several tau * v)"},
                {"step_mm", 50, "mm", "length at the high flow"},
                {"tail_mm", 55, "mm", "length at the low flow after the step"},
                {"low_flow", 0.8, "", "low flow, relative to the profile's line width x layer height"},
                {"high_flow", 1.5, "", "high flow, relative"},
                {"spacing_mm", 6, "mm", "distance between the lines"},
                {"center_x_mm", kMachineDefault, "mm", "middle of the lines in x (default: middle of the travel)", ParamDomain::any, kMaxLengthMm},
                {"first_y_mm", kMachineDefault, "mm", "y of the first line (default: 50 mm below the middle)", ParamDomain::any, kMaxLengthMm},
                {"z_mm", 0.2, "mm", "layer height / nozzle height"},
                {"retract_mm", 0.8, "mm", "retraction after each line (primed again before the next)"},
                {"accel_mm_s2", 1000, "mm/s^2", "print acceleration"},
                hotend},
               {},
               false});
  s.push_back({"axis-sweep",
               "resonance sweep like Klipper's TEST_RESONANCES: back-and-forth moves whose acceleration is "
               "accel_per_hz * f while f rises at hz_per_sec; the accelerometer is recorded",
               {{"freq_start_hz", 10, "Hz", "first frequency", ParamDomain::positive, kMaxFreqHz},
                {"freq_end_hz", 100, "Hz", "last frequency", ParamDomain::positive, kMaxFreqHz},
                {"hz_per_sec", 2, "Hz/s", "sweep rate", ParamDomain::positive, kMaxFreqHz},
                {"accel_per_hz", 60, "mm/s^2/Hz", "acceleration amplitude per Hz", ParamDomain::positive, kMaxAccelMmS2 / kMaxFreqHz},
                {"center_mm", kMachineDefault, "mm", "position of the swept axis (default: middle of its travel)", ParamDomain::any, kMaxLengthMm},
                {"other_mm", kMachineDefault, "mm", "position of the other horizontal axis (default: middle)", ParamDomain::any, kMaxLengthMm},
                {"travel_speed_mm_s", 100, "mm/s", "speed of the move to the start position", ParamDomain::positive, kMaxSpeedMmS},
                {"settle_s", 0.3, "s", "recorded rest before and after the sweep", ParamDomain::non_negative, kMaxTimeS}},
               {"accelerometer"},
               true});
  s.push_back({"axis-rectangle",
               "the overshoot test of Hemminger, Improvements and Characterization of Error, Speed, and Capabilities "
               "in Low-Cost Additive Manufacturing Systems, UCLA, 2022: an XY rectangle with pauses at the corners, "
               "repeated; each axis sees step motions; the accelerometer is recorded (analyze: tunekit overshoot)",
               {{"width_mm", 40, "mm", "rectangle size along x", ParamDomain::positive, kMaxLengthMm},
                {"height_mm", 40, "mm", "rectangle size along y", ParamDomain::positive, kMaxLengthMm},
                {"speed_mm_s", 100, "mm/s", "move speed", ParamDomain::positive, kMaxSpeedMmS},
                {"accel_mm_s2", 3000, "mm/s^2", "move acceleration", ParamDomain::positive, kMaxAccelMmS2},
                {"repeats", 5, "", "rectangles (Hemminger 2022: 5)", ParamDomain::count, 10000},
                {"pause_s", 0.3, "s", "pause at each corner", ParamDomain::positive, kMaxTimeS}},
               {"accelerometer"},
               false});
  s.push_back({"test-pattern",
               "test prints (pads for photos, line steps, rings) on one layer, ordered by the grid-based coverage "
               "planner after Li and Yao, Coverage Path Planning Application on FDM 3D Printer, USC, 2018 (fewer "
               "travels and retractions than a zigzag; zigzag=1 prints the zigzag for comparison)",
               {{"pads", 4, "", "filled squares for photos", ParamDomain::count, 100},
                {"pad_mm", 20, "mm", "pad size"},
                {"line_steps", 5, "", "single lines of rising length", ParamDomain::count, 100},
                {"line_mm", 30, "mm", "longest line"},
                {"rings", 2, "", "two-line-wide rings", ParamDomain::count, 100},
                {"ring_radius_mm", 12, "mm", "ring radius"},
                {"speed_mm_s", 40, "mm/s", "print speed"},
                {"travel_speed_mm_s", 150, "mm/s", "travel speed"},
                {"accel_mm_s2", 1500, "mm/s^2", "acceleration"},
                {"z_mm", 0.2, "mm", "layer height / nozzle height"},
                {"zigzag", 0, "", "1: plain zigzag order instead of the coverage planner", ParamDomain::non_negative, 1},
                hotend},
               {},
               false});
  return s;
}

double mid(const MachineProfile& p, const std::string& axis) {
  const auto& a = p.axis(axis);
  return 0.5 * (a.min_mm + a.max_mm);
}

std::string num(double v, int decimals = 4) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

/// How the firmware runs an extrude-only feed: Klipper brings every extrude-only move to a full
/// stop (klippy/toolhead.py Move.calc_junction returns early unless both moves are kinematic),
/// Marlin and RepRapFirmware blend consecutive extrude-only moves in the same direction.
/// `accel_mm_s2` is the acceleration the firmware applies to them; `max_len_mm` the longest
/// extrude-only move it accepts.
struct FeedPlan {
  bool stops = false;
  double accel_mm_s2 = 0;
  double max_len_mm = 50;
};

/// One constant-feed segment of `duration_s` at `feed_mm_s`, split into moves of at most
/// max_len_mm. When the firmware stops after each move, the move's speed is raised so that the
/// move with its ramps (d / v + v / a) still takes its share of the duration and delivers its
/// share of the length: the staircase keeps its labelled timing.
void feed_move(std::vector<std::string>& g, const FeedPlan& fp, double feed_mm_s, double duration_s) {
  const double total = feed_mm_s * duration_s;
  const int n = std::max(1, static_cast<int>(std::ceil(total / fp.max_len_mm - 1e-9)));
  const double d = total / n, dt = duration_s / n;
  double v = feed_mm_s;
  if (fp.stops) {
    const double a = fp.accel_mm_s2;
    const double disc = a * a * dt * dt - 4 * a * d;
    if (disc < 0)
      throw InputError(fmt::format(
          "a {:.4g} s feed segment of {:.4g} mm cannot keep its timing on a firmware that stops after every "
          "extrude-only move (Klipper) at {:.0f} mm/s^2: it needs at least {:.0f} mm/s^2 (4 d / t^2) or a longer segment",
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
                        const MachineProfile& profile, const Dialect& d) {
  FeedPlan fp;
  fp.max_len_mm = profile.extruder.max_extrude_only_distance_mm;
  switch (d.firmware()) {
    case Firmware::klipper:
      g.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={}", num(a, 0)));
      restore.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={}", num(profile.print.max_accel_mm_s2, 0)));
      fp.stops = true;
      fp.accel_mm_s2 = std::min(a, profile.extruder.max_accel_mm_s2);
      break;
    case Firmware::reprapfirmware:
      g.push_back(fmt::format("M201 E{}", num(a, 0)));
      restore.push_back(fmt::format("M201 E{}", num(profile.state.max_accel_e_mm_s2, 0)));
      fp.accel_mm_s2 = a;
      break;
    default:
      g.push_back(fmt::format("M204 R{}", num(a, 0)));
      restore.push_back(fmt::format("M204 R{}", num(profile.state.retract_accel_mm_s2, 0)));
      fp.accel_mm_s2 = a;
      break;
  }
  return fp;
}

FeedPlan liquefier_prologue(std::vector<std::string>& g, std::vector<std::string>& restore,
                            const std::map<std::string, double>& p, const MachineProfile& profile, const Dialect& d) {
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
/// axis), RepRapFirmware M593 P"none".
void shaping_off(const MachineProfile& profile, const Dialect& d, std::vector<std::string>& prologue,
                 std::vector<std::string>& restore, nlohmann::json& changed) {
  const auto& shaper = profile.state.shaper;
  if (shaper.empty()) return;
  switch (d.firmware()) {
    case Firmware::klipper: {
      prologue.push_back("SET_INPUT_SHAPER SHAPER_FREQ_X=0 SHAPER_FREQ_Y=0");
      std::string r = "SET_INPUT_SHAPER";
      for (const auto& [ax, v] : shaper) {
        const auto sv = split_state_shaper(v);
        const std::string U = ax == "x" ? "X" : "Y";
        r += fmt::format(" SHAPER_TYPE_{}={} SHAPER_FREQ_{}={} DAMPING_RATIO_{}={}", U, sv.type, U, sv.freq, U, sv.zeta);
      }
      restore.push_back(r);
      changed.push_back("input_shaper");
      break;
    }
    case Firmware::reprapfirmware: {
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

}  // namespace

const std::vector<ProtocolSpec>& protocol_specs() {
  static const std::vector<ProtocolSpec> specs = make_specs();
  return specs;
}

const ProtocolSpec& protocol_spec(const std::string& name) {
  for (const auto& s : protocol_specs())
    if (s.name == name) return s;
  std::string known;
  for (const auto& s : protocol_specs()) known += (known.empty() ? "" : ", ") + s.name;
  throw InputError(fmt::format("unknown protocol '{}' (known: {})", name, known));
}

nlohmann::json Experiment::to_json() const {
  nlohmann::json j;
  j["protocol"] = protocol;
  if (!axis.empty()) j["axis"] = axis;
  j["params"] = params;
  j["sensors"] = sensors;
  j["gcode_lines"] = gcode.size();
  j["estimated_duration_s"] = estimated_duration_s;
  j["excitation"] = excitation;
  return j;
}

namespace {

void check_param_domain(const std::string& protocol, const ProtocolParam& prm, double v) {
  if (!std::isfinite(v))
    throw InputError(fmt::format("{} parameter {} must be a finite number, not {}", protocol, prm.name, v));
  const char* why = nullptr;
  switch (prm.domain) {
    case ParamDomain::positive:
      if (!(v > 0)) why = "must be positive";
      break;
    case ParamDomain::non_negative:
      if (v < 0 || std::signbit(v)) why = "must not be negative";
      break;
    case ParamDomain::count:
      if (!(v >= 1) || v != std::floor(v)) why = "must be a whole number >= 1";
      break;
    case ParamDomain::any:
      break;
  }
  if (!why && std::abs(v) > prm.max_value) why = "is beyond its plausible range";
  if (why) {
    const std::string lower = prm.domain == ParamDomain::any        ? fmt::format("-{:g}", prm.max_value)
                              : prm.domain == ParamDomain::positive ? std::string("above 0")
                              : prm.domain == ParamDomain::count    ? std::string("1")
                                                                    : std::string("0");
    throw InputError(fmt::format("{} parameter {} {} (accepted: {} to {:g}{}), not {:g}", protocol, prm.name, why, lower,
                                 prm.max_value, prm.unit.empty() ? "" : " " + prm.unit, v));
  }
}

/// Refuses a plan (lines and machine time worked out from the parameters) beyond the caps.
void check_plan(const std::string& protocol, double lines, double duration_s, const ProtocolLimits& limits) {
  if (!(duration_s <= limits.max_duration_s)) {
    const std::string how_long = std::isfinite(duration_s) ? fmt::format("{:.4g} s ({:.3g} h)", duration_s, duration_s / 3600)
                                                           : std::string("an unbounded time");
    throw InputError(fmt::format("{} would take {} of machine time; the limit is {:g} s (change the parameters, or "
                                 "raise it with --max-duration)",
                                 protocol, how_long, limits.max_duration_s));
  }
  if (!(lines <= static_cast<double>(limits.max_lines)))
    throw InputError(fmt::format("{} would need {:.4g} G-code lines; the limit is {} (change the parameters, or "
                                 "raise it with --max-lines)",
                                 protocol, lines, limits.max_lines));
}

}  // namespace

Experiment build_experiment(const std::string& protocol, const std::map<std::string, double>& overrides,
                            const std::string& axis_in, const MachineProfile& profile, const Dialect& d,
                            const ProtocolLimits& limits) {
  const auto& spec = protocol_spec(protocol);
  Experiment e;
  e.protocol = protocol;
  e.sensors = spec.sensors;
  for (const auto& prm : spec.params) e.params[prm.name] = prm.default_value;
  for (const auto& [k, v] : overrides) {
    if (!e.params.count(k)) {
      std::string known;
      for (const auto& prm : spec.params) known += (known.empty() ? "" : ", ") + prm.name;
      throw InputError(fmt::format("protocol {} has no parameter '{}' (parameters: {})", protocol, k, known));
    }
    e.params[k] = v;
  }
  // Every parameter in its domain (defaults that come from the machine are NaN until filled in).
  for (const auto& prm : spec.params)
    if (!(std::isnan(prm.default_value) && !overrides.count(prm.name))) check_param_domain(protocol, prm, e.params.at(prm.name));
  auto& p = e.params;
  auto& g = e.gcode;
  // A second bound while generating, whatever the plan said: the memory a protocol takes stays
  // bounded even if a plan below were wrong.
  auto guard = [&] {
    if (g.size() > limits.max_lines + 64)
      throw InputError(fmt::format("{} exceeds {} G-code lines while being generated (--max-lines)", protocol, limits.max_lines));
  };
  g.push_back(fmt::format("; tunekit {} on {}", protocol, profile.name));

  if (protocol == "liquefier-step") {
    const double cycles_d = p.at("cycles");
    check_plan(protocol, 2 * cycles_d + 8, p.at("settle_s") + 2 * cycles_d * p.at("hold_s"), limits);
    const int cycles = static_cast<int>(cycles_d);
    std::vector<std::string> restore;
    const FeedPlan fp = liquefier_prologue(g, restore, p, profile, d);
    record_feed_plan(e, fp);
    g.push_back(";@record load_cell on");
    feed_move(g, fp, p["feed_low_mm_s"], p["settle_s"]);
    for (int c = 0; c < cycles; ++c) {
      feed_move(g, fp, p["feed_high_mm_s"], p["hold_s"]);
      feed_move(g, fp, p["feed_low_mm_s"], p["hold_s"]);
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
    epilogue(g, restore);
  } else if (protocol == "liquefier-flow-sweep") {
    const double area = profile.filament_area_mm2();
    if (std::isnan(p["flow_max_mm3_s"])) {
      double limit = std::numeric_limits<double>::infinity();
      if (profile.extruder.max_flow_mm3_s > 0) limit = profile.extruder.max_flow_mm3_s;
      if (profile.extruder.max_velocity_mm_s > 0) limit = std::min(limit, profile.extruder.max_velocity_mm_s * area);
      if (!std::isfinite(limit))
        throw InputError("liquefier-flow-sweep needs the hot end's range: give flow_max_mm3_s, or max_flow_mm3_s in the "
                         "profile's [extruder]");
      p["flow_max_mm3_s"] = 0.9 * limit;
    }
    if (std::isnan(p["flow_min_mm3_s"])) p["flow_min_mm3_s"] = p["flow_max_mm3_s"] / 10;
    const auto plan = plan_flow_sweep(p.at("flow_min_mm3_s"), p.at("flow_max_mm3_s"), static_cast<int>(p.at("levels")),
                                      static_cast<int>(p.at("cycles")), p.at("expected_tau_s"), p.at("hold_taus"),
                                      p.at("settle_s"));
    double lines = 10;
    for (double q : plan.sequence_mm3_s)
      lines += std::ceil(q / area * plan.hold_s / std::max(profile.extruder.max_extrude_only_distance_mm, 1e-3)) + 1;
    check_plan(protocol, lines, plan.duration_s(), limits);
    std::vector<std::string> restore;
    const FeedPlan fp = liquefier_prologue(g, restore, p, profile, d);
    record_feed_plan(e, fp);
    nlohmann::json levels = nlohmann::json::array();
    std::string level_text;
    for (double q : plan.measured_flows_mm3_s) {
      levels.push_back(q);
      level_text += (level_text.empty() ? "" : ", ") + num(q, 3);
    }
    e.excitation["measured_flows_mm3_s"] = levels;
    e.excitation["turning_flows_mm3_s"] = {plan.flow_min_mm3_s, plan.flow_max_mm3_s};
    e.excitation["hold_s"] = plan.hold_s;
    g.push_back(fmt::format("; flow levels {} mm^3/s (ratio {}), turning at {} and {} mm^3/s, {} s each",
                            level_text, num(plan.ratio, 3), num(plan.flow_min_mm3_s),
                            num(plan.flow_max_mm3_s), num(plan.hold_s, 3)));
    g.push_back(";@record load_cell on");
    for (std::size_t i = 0; i < plan.sequence_mm3_s.size(); ++i) {
      feed_move(g, fp, plan.sequence_mm3_s[i] / area, i == 0 ? plan.settle_s : plan.hold_s);
      guard();
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
    epilogue(g, restore);
  } else if (protocol == "liquefier-sine" || protocol == "liquefier-chirp") {
    const double mean = p.at("feed_mean_mm_s");
    const double amp = p.at("amplitude_mm_s");
    if (amp >= mean) throw InputError("amplitude_mm_s must be in [0, feed_mean_mm_s) so the feed stays positive");
    const double seg = p.at("segment_s");
    if (protocol == "liquefier-chirp" && p.at("expected_tau_s") != 0) {
      const auto plan = plan_liquefier_chirp(p.at("expected_tau_s"), seg);
      for (const auto& [k, v] : {std::pair{"freq_min_hz", plan.freq_min_hz}, std::pair{"freq_max_hz", plan.freq_max_hz},
                                 std::pair{"duration_s", plan.duration_s}, std::pair{"settle_s", plan.settle_s}})
        if (!overrides.count(k)) p[k] = v;
    }
    const double f0 = p.at("freq_min_hz"), f1 = p.at("freq_max_hz");
    std::vector<std::string> restore;
    FeedPlan fp;
    if (protocol == "liquefier-sine") {
      const int n = static_cast<int>(p.at("freq_count"));
      const double periods = p.at("periods");
      auto freq = [&](int i) { return n == 1 ? f0 : f0 * std::pow(f1 / f0, static_cast<double>(i) / (n - 1)); };
      double lines = 0, seconds = 3;
      for (int i = 0; i < n; ++i) {
        const double f = freq(i), dt = std::min(seg, 1.0 / (20 * f));
        lines += std::ceil(periods / f / dt) + 1;
        seconds += periods / f;
      }
      check_plan(protocol, lines + 10, seconds, limits);
      fp = liquefier_prologue(g, restore, p, profile, d);
      record_feed_plan(e, fp);
      g.push_back(";@record load_cell on");
      feed_move(g, fp, mean, 2.0);  // steady state first
      for (int i = 0; i < n; ++i) {
        const double f = freq(i);
        const double dt = std::min(seg, 1.0 / (20 * f));
        const long steps = static_cast<long>(std::ceil(periods / f / dt));
        g.push_back(fmt::format("; dwell at {} Hz", num(f, 4)));
        for (long k = 0; k < steps; ++k) {
          feed_move(g, fp, mean + amp * std::sin(2 * std::numbers::pi * f * (static_cast<double>(k) + 0.5) * dt), dt);
          guard();
        }
      }
    } else {
      const double T = p.at("duration_s");
      check_plan(protocol, std::ceil(T / seg) + 10, T + p.at("settle_s") + 1, limits);
      fp = liquefier_prologue(g, restore, p, profile, d);
      record_feed_plan(e, fp);
      g.push_back(";@record load_cell on");
      feed_move(g, fp, mean, p.at("settle_s"));  // steady state first
      const long steps = static_cast<long>(std::ceil(T / seg));
      for (long k = 0; k < steps; ++k) {
        const double t = (static_cast<double>(k) + 0.5) * seg;
        const double phase = 2 * std::numbers::pi * (f0 * t + 0.5 * (f1 - f0) / T * t * t);
        feed_move(g, fp, mean + amp * std::sin(phase), seg);
        guard();
      }
    }
    feed_move(g, fp, mean, 1.0);
    g.push_back(d.wait_for_moves());
    g.push_back(";@record load_cell off");
    epilogue(g, restore);
  } else if (protocol == "ring-print") {
    const double R = p.at("radius_mm"), v = p.at("speed_mm_s"), A = p.at("amplitude");
    if (A >= 1) throw InputError(fmt::format("ring-print parameter amplitude must be below 1 so the extrusion stays positive, not {:g}", A));
    const int N = static_cast<int>(p.at("periods"));
    const int segs = std::max(12, static_cast<int>(p.at("segments")));
    check_plan(protocol, segs + 12.0, 2 * std::numbers::pi * R / v, limits);
    if (std::isnan(p["center_x_mm"])) p["center_x_mm"] = mid(profile, "x");
    if (std::isnan(p["center_y_mm"])) p["center_y_mm"] = mid(profile, "y");
    const double cx = p["center_x_mm"], cy = p["center_y_mm"];
    const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
    g.push_back(fmt::format("; f = N v / (2 pi R) = {} Hz", num(N * v / (2 * std::numbers::pi * R), 4)));
    g.push_back("G28");
    g.push_back("G90");
    g.push_back("M83 ; relative extrusion");
    if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
    g.push_back(d.set_accel(std::min(p.at("accel_mm_s2"), profile.axis("z").max_accel_mm_s2)));
    g.push_back(fmt::format("G1 Z{} F{}", num(p.at("z_mm")), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
    g.push_back(d.set_accel(p.at("accel_mm_s2")));
    g.push_back(fmt::format("G1 X{} Y{} F{}", num(cx + R), num(cy), num(std::min(100.0, v * 3) * 60, 1)));
    const double seg_len = 2 * R * std::sin(std::numbers::pi / segs);
    for (int k = 1; k <= segs; ++k) {
      const double th = 2 * std::numbers::pi * k / segs, th_mid = 2 * std::numbers::pi * (k - 0.5) / segs;
      const double e = e_per_mm * seg_len * (1 + A * std::sin(N * th_mid));
      g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(cx + R * std::cos(th)), num(cy + R * std::sin(th)), num(e, 5),
                              num(v * 60, 1)));
    }
    g.push_back(d.wait_for_moves());
  } else if (protocol == "line-steps") {
    if (std::isnan(p["center_x_mm"])) p["center_x_mm"] = mid(profile, "x");
    if (std::isnan(p["first_y_mm"])) p["first_y_mm"] = mid(profile, "y") - 50;
    append_line_steps_gcode(g, p, profile, d);
  } else if (protocol == "axis-sweep") {
    if (axis_in != "x" && axis_in != "y") throw InputError(fmt::format("axis-sweep needs --axis x or y, not '{}'", axis_in));
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
    if (d.firmware() == Firmware::marlin || d.firmware() == Firmware::prusa) {
      // Marlin joins a move with fewer than MIN_STEPS_PER_SEGMENT steps with the next one
      // (planner.cpp _buffer_steps; Configuration_adv.h MIN_STEPS_PER_SEGMENT 6).
      const double spm = axis_in == "x" ? profile.state.steps_per_mm_x : profile.state.steps_per_mm_y;
      min_len = limits::kMarlinMinStepsPerSegment / spm;
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
              f, limits::kMarlinMinStepsPerSegment, min_len, a, axis_max_accel));
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
      case Firmware::klipper:
        // As Klipper's own TEST_RESONANCES (klippy/extras/resonance_tester.py:194-199):
        // MINIMUM_CRUISE_RATIO=0 and input shaping off.
        prologue.push_back("SET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO=0");
        restore.push_back(fmt::format("SET_VELOCITY_LIMIT ACCEL={} MINIMUM_CRUISE_RATIO={}",
                                      num(profile.print.max_accel_mm_s2, 0), num(profile.state.minimum_cruise_ratio, 3)));
        changed.push_back("minimum_cruise_ratio");
        break;
      case Firmware::reprapfirmware:
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
    if (d.firmware() != Firmware::klipper && accel > profile.state.max_accel_xy_mm_s2) {
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
      for (const auto& corner : {std::pair{x0 + w, y0}, std::pair{x0 + w, y0 + h}, std::pair{x0, y0 + h}, std::pair{x0, y0}}) {
        g.push_back(fmt::format("G1 X{} Y{} F{}", num(corner.first), num(corner.second), num(v * 60, 1)));
        g.push_back(fmt::format("G4 P{}", pause_ms));
      }
    }
    g.push_back(d.wait_for_moves());
    g.push_back(";@record accelerometer off");
    epilogue(g, restore);
  } else if (protocol == "test-pattern") {
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
    // The safety check counts a retraction's filament speed against the hot end's flow limit.
    double retract = mo.retract_speed_mm_s;
    if (profile.extruder.max_flow_mm3_s > 0) retract = std::min(retract, 0.9 * profile.extruder.max_flow_mm3_s / profile.filament_area_mm2());
    if (profile.extruder.max_velocity_mm_s > 0) retract = std::min(retract, 0.9 * profile.extruder.max_velocity_mm_s);
    mo.retract_speed_mm_s = retract;
    const auto plan = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "zigzag" : "pce", mo);
    const auto other = plan_test_patterns(set, profile, p.at("zigzag") != 0 ? "pce" : "zigzag", mo);
    for (const auto* pl : {&plan, &other})
      g.push_back(fmt::format("; {} order: print {} mm, travel {} mm, {} retractions, estimated {} s", pl->planner,
                              num(pl->stats.print_mm, 1), num(pl->stats.travel_mm, 1), pl->stats.retractions,
                              num(pl->stats.time_s, 1)));
    const double e_per_mm = profile.line_area_mm2() / profile.filament_area_mm2();
    g.push_back("G28");
    g.push_back("G90");
    g.push_back("M83 ; relative extrusion");
    if (p.at("hotend_c") > 0) g.push_back(d.set_hotend(p.at("hotend_c"), true));
    g.push_back(d.set_accel(std::min(mo.accel_mm_s2, profile.axis("z").max_accel_mm_s2)));
    g.push_back(fmt::format("G1 Z{} F{}", num(p.at("z_mm")), num(std::min(10.0, profile.axis("z").max_velocity_mm_s) * 60, 1)));
    g.push_back(d.set_accel(mo.accel_mm_s2));
    const auto& first = plan.moves.front();
    g.push_back(fmt::format("G0 X{} Y{} F{}", num(first.x0), num(first.y0), num(mo.travel_speed_mm_s * 60, 1)));
    for (const auto& m : plan.moves) {
      if (m.extrude) {
        g.push_back(fmt::format("G1 X{} Y{} E{} F{}", num(m.x1), num(m.y1),
                                num(e_per_mm * std::hypot(m.x1 - m.x0, m.y1 - m.y0), 5), num(mo.print_speed_mm_s * 60, 1)));
      } else {
        g.push_back(fmt::format("G1 E-{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
        g.push_back(fmt::format("G0 X{} Y{} F{}", num(m.x1), num(m.y1), num(mo.travel_speed_mm_s * 60, 1)));
        g.push_back(fmt::format("G1 E{} F{}", num(mo.retract_mm), num(mo.retract_speed_mm_s * 60, 1)));
      }
    }
    g.push_back(d.wait_for_moves());
  }
  e.estimated_duration_s = estimate_gcode_duration_s(g);
  return e;
}

}  // namespace tunekit::protocols
