// The protocol table: every protocol's parameters (defaults, units, domains, plausibility caps)
// and sensors, and its lookup by name.
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

#include "sweep_moves.hpp"

namespace tunekit::protocols {
namespace {

constexpr double kMachineDefault = std::numeric_limits<double>::quiet_NaN();

// Plausibility caps of the parameters (ProtocolParam::max_value). They are far above anything
// an experiment on an FFF printer asks for and far below where the protocol arithmetic (and its
// conversion of counts and milliseconds to whole numbers) could overflow; the machine's own
// limits are checked on the generated G-code by the safety gate.
constexpr double kMaxFeedMmS = 1000;      // filament feed, mm/s
constexpr double kMaxSpeedMmS = 10000;    // toolhead speed, mm/s
constexpr double kMaxAccelMmS2 = 1e6;     // mm/s^2
constexpr double kMaxTimeS = 3600;        // one settle/hold/pause time, s
constexpr double kMaxFreqHz = 1000;       // excitation frequency, Hz
constexpr double kMaxLengthMm = 10000;    // sizes and positions, mm
constexpr double kMaxTemperatureC = 500;  // set temperature, degC (the profile's hotend_max_c applies too)
constexpr double kMaxFlowMm3S = 1000;     // volumetric flow, mm^3/s
constexpr double kMaxLoadKg = 20;         // a mass placed on a bed, kg

/// The hot end's set temperature, a parameter of every protocol that extrudes.
ProtocolParam hotend_param() {
  return {"hotend_c",
          210,
          "degC",
          "hot-end temperature set (and waited for) first; 0 leaves the heater alone",
          ParamDomain::non_negative,
          kMaxTemperatureC};
}

/// The liquefier's experiments with the load cell (1/2): the steps and the flow sweep.
void add_liquefier_step_specs(std::vector<ProtocolSpec>& s) {
  const ProtocolParam hotend = hotend_param();
  s.push_back(
      {Protocol::liquefier_step,
       "liquefier-step",
       "extrusion-rate steps (low, then high/low cycles) with the load cell recording the filament force",
       {{"feed_low_mm_s", kMachineDefault, "mm/s",
         "filament feed before and between steps (default: 1, or a third of feed_high_mm_s when lower)",
         ParamDomain::positive, kMaxFeedMmS},
        {"feed_high_mm_s", kMachineDefault, "mm/s",
         "filament feed during a step (default: 3, or 90 % of the extruder's and the hot end's limit when lower)",
         ParamDomain::positive, kMaxFeedMmS},
        {"settle_s", 3.0, "s", "time at the low feed before the first step", ParamDomain::positive, kMaxTimeS},
        {"hold_s", 3.0, "s", "time at each level (several tau)", ParamDomain::positive, kMaxTimeS},
        {"cycles", 2, "", "number of low -> high -> low cycles", ParamDomain::count, 1000},
        {"accel_mm_s2", kMachineDefault, "mm/s^2",
         "filament acceleration of the feed changes (default: 2000, or the extruder's max_accel_mm_s2 when lower)",
         ParamDomain::positive, kMaxAccelMmS2},
        hotend},
       {"load_cell"},
       false});
  s.push_back(
      {Protocol::liquefier_flow_sweep,
       "liquefier-flow-sweep",
       "feed steps up and down through flow levels spread over the hot end's range (each level reached "
       "from below and from above), load cell recorded; tau, K, theta per level and their trend with flow",
       {{"levels", 6, "", "measured flow levels, spaced geometrically between the turning flows", ParamDomain::count,
         16},
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
        {"accel_mm_s2", kMachineDefault, "mm/s^2",
         "filament acceleration of the feed changes (default: 2000, or the extruder's max_accel_mm_s2 when lower)",
         ParamDomain::positive, kMaxAccelMmS2},
        hotend},
       {"load_cell"},
       false});
}

/// The liquefier's experiments with the load cell (2/2): the sine dwells and the chirp.
void add_liquefier_periodic_specs(std::vector<ProtocolSpec>& s) {
  const ProtocolParam hotend = hotend_param();
  s.push_back(
      {Protocol::liquefier_sine,
       "liquefier-sine",
       "sine-dwell list: the feed oscillates around a mean at log-spaced frequencies, load cell recorded",
       {{"feed_mean_mm_s", kMachineDefault, "mm/s",
         "mean filament feed (default: 2, lowered with the amplitude so that the highest feed stays within 90 % of "
         "the extruder's and the hot end's limits)",
         ParamDomain::positive, kMaxFeedMmS},
        {"amplitude_mm_s", kMachineDefault, "mm/s",
         "feed oscillation amplitude (below the mean; default: 1, or lower with the mean)", ParamDomain::non_negative,
         kMaxFeedMmS},
        {"freq_min_hz", 0.2, "Hz", "lowest frequency", ParamDomain::positive, kMaxFreqHz},
        {"freq_max_hz", kMachineDefault, "Hz",
         "highest frequency (default: 2, or lower where a period must hold 20 staircase steps of segment_s)",
         ParamDomain::positive, kMaxFreqHz},
        {"freq_count", 5, "", "number of frequencies (log-spaced)", ParamDomain::count, 1000},
        {"periods", 4, "", "periods per frequency", ParamDomain::positive, 10000},
        {"segment_s", kMachineDefault, "s",
         "duration of one constant-feed move of the staircase (default: 0.02, or longer where the firmware stops "
         "after every extrude-only move and the extruder's acceleration needs it)",
         ParamDomain::positive, 10},
        {"accel_mm_s2", kMachineDefault, "mm/s^2",
         "filament acceleration between segments (default: 3000, or the extruder's max_accel_mm_s2 when lower)",
         ParamDomain::positive, kMaxAccelMmS2},
        hotend},
       {"load_cell"},
       false});
  s.push_back(
      {Protocol::liquefier_chirp,
       "liquefier-chirp",
       "linear chirp of the feed from freq_min_hz to freq_max_hz, load cell recorded",
       {{"feed_mean_mm_s", kMachineDefault, "mm/s",
         "mean filament feed (default: 2, lowered with the amplitude so that the highest feed stays within 90 % of "
         "the extruder's and the hot end's limits)",
         ParamDomain::positive, kMaxFeedMmS},
        {"amplitude_mm_s", kMachineDefault, "mm/s",
         "feed oscillation amplitude (below the mean; default: 1, or lower with the mean)", ParamDomain::non_negative,
         kMaxFeedMmS},
        {"freq_min_hz", 0.1, "Hz", "start frequency", ParamDomain::positive, kMaxFreqHz},
        {"freq_max_hz", 3.0, "Hz", "end frequency", ParamDomain::positive, kMaxFreqHz},
        {"duration_s", 20, "s", "chirp duration", ParamDomain::positive, kMaxTimeS},
        {"settle_s", 2.0, "s", "steady feed at the mean before the chirp", ParamDomain::positive, kMaxTimeS},
        {"expected_tau_s", 0, "s",
         "expected liquefier time constant (0: none); when given, the frequency range, duration and settle "
         "time not set explicitly are sized from its corner 1/(2 pi tau)",
         ParamDomain::non_negative, kMaxTimeS},
        {"segment_s", kMachineDefault, "s",
         "duration of one constant-feed move of the staircase (default: 0.02, or longer where the firmware stops "
         "after every extrude-only move and the extruder's acceleration needs it)",
         ParamDomain::positive, 10},
        {"accel_mm_s2", kMachineDefault, "mm/s^2",
         "filament acceleration between segments (default: 3000, or the extruder's max_accel_mm_s2 when lower)",
         ParamDomain::positive, kMaxAccelMmS2},
        hotend},
       {"load_cell"},
       false});
}

/// Printed tests measured from a photo: Holtrup's ring and the camera path's line test.
void add_print_specs(std::vector<ProtocolSpec>& s) {
  const ProtocolParam hotend = hotend_param();
  s.push_back(
      {Protocol::ring_print,
       "ring-print",
       "Holtrup's frequency test (Tuning liquefier dynamics, MSc thesis, University of Twente, 2019): a ring "
       "printed at constant speed with the extrusion modulated by (1 + amplitude sin(periods theta)); "
       "f = periods v / (2 pi R). Measure the width with 'tunekit linewidth'",
       {{"radius_mm", 30, "mm", "ring radius R (Holtrup 2019, appendix D: 30 mm)", ParamDomain::positive, kMaxLengthMm},
        {"center_x_mm", kMachineDefault, "mm", "ring centre x (default: middle of the travel)", ParamDomain::any,
         kMaxLengthMm},
        {"center_y_mm", kMachineDefault, "mm", "ring centre y (default: middle of the travel)", ParamDomain::any,
         kMaxLengthMm},
        {"speed_mm_s", 20, "mm/s", "print speed v", ParamDomain::positive, kMaxSpeedMmS},
        {"periods", 8, "", "sine periods N around the ring", ParamDomain::count, 10000},
        {"amplitude", 0.2, "", "relative extrusion modulation A (below 1, so the extrusion stays positive)",
         ParamDomain::non_negative, 1},
        {"segments", 360, "", "straight segments per ring (at least 12)", ParamDomain::count, 100000},
        {"z_mm", 0.2, "mm", "layer height / nozzle height of the ring", ParamDomain::positive, kMaxLengthMm},
        {"accel_mm_s2", kMachineDefault, "mm/s^2", "print acceleration (default: 1000, or the axes' limit)",
         ParamDomain::positive, kMaxAccelMmS2},
        hotend},
       {},
       false});
  s.push_back({Protocol::line_steps,
               "line-steps",
               "the camera path's line test: straight lines along +X whose flow steps low -> high -> low part-way; "
               "photographed, the width along each line is the liquefier's step response (t = s / v)",
               {{"speed_mm_s", 20, "mm/s", "print speed v"},
                {"lines", 3, "", "number of lines (printed one below the other)", ParamDomain::count, 100},
                {"lead_mm", 45, "mm", "length at the low flow before the step (several tau * v)"},
                {"step_mm", 50, "mm", "length at the high flow"},
                {"tail_mm", 55, "mm", "length at the low flow after the step"},
                {"low_flow", 0.9, "", "low flow, relative to the profile's line width x layer height"},
                {"high_flow", 1.3, "",
                 "high flow, relative (at most 1.6 times the low flow: the photo measurement takes a line wider than "
                 "1.6 times its median for two merged beads)"},
                {"spacing_mm", 6, "mm", "distance between the lines"},
                {"center_x_mm", kMachineDefault, "mm", "middle of the lines in x (default: middle of the travel)",
                 ParamDomain::any, kMaxLengthMm},
                {"first_y_mm", kMachineDefault, "mm", "y of the first line (default: 50 mm below the middle)",
                 ParamDomain::any, kMaxLengthMm},
                {"z_mm", 0.2, "mm", "layer height / nozzle height"},
                {"retract_mm", 0.8, "mm", "retraction after each line (primed again before the next)"},
                {"rest_mm", 10, "mm",
                 "run-up without extrusion before the first line, which then starts from rest (its width rises from "
                 "zero: the melt stored at the low flow); 0: none",
                 ParamDomain::non_negative, kMaxLengthMm},
                {"rest_dwell_s", 10, "s", "wait before the run-up while the primed melt comes to rest",
                 ParamDomain::non_negative, kMaxTimeS},
                {"accel_mm_s2", kMachineDefault, "mm/s^2", "print acceleration (default: 1000, or the axes' limit)"},
                hotend},
               {},
               false});
}

/// The axes' experiments with the accelerometer: the resonance sweep and the overshoot rectangle.
void add_axis_specs(std::vector<ProtocolSpec>& s) {
  s.push_back(
      {Protocol::axis_sweep,
       "axis-sweep",
       "resonance sweep like Klipper's TEST_RESONANCES (resonance_tester.py, 2024-12 to 2026-08): back-and-forth "
       "moves whose acceleration is accel_per_hz * f while f rises at hz_per_sec, with Klipper's slow sweeping "
       "motion added on Klipper; the accelerometer is recorded",
       {{"freq_start_hz", 10, "Hz", "first frequency", ParamDomain::positive, kMaxFreqHz},
        {"freq_end_hz", kMachineDefault, "Hz",
         "last frequency (default: 100; on Marlin lower where a half period would need more steps than "
         "MIN_STEPS_PER_SEGMENT at an acceleration above the axis' limit)",
         ParamDomain::positive, kMaxFreqHz},
        {"hz_per_sec", 2, "Hz/s", "sweep rate", ParamDomain::positive, kMaxFreqHz},
        {"accel_per_hz", kMachineDefault, "mm/s^2/Hz",
         "acceleration amplitude per Hz (default: Klipper's 60, or lower so that accel_per_hz x freq_end_hz stays "
         "within what the axis' acceleration limit leaves beside the sweeping motion; a larger value is held at that "
         "limit above the frequency where it meets it)",
         ParamDomain::positive, kMaxAccelMmS2 / kMaxFreqHz},
        {"sweeping_accel", kMachineDefault, "mm/s^2",
         "acceleration of the slow sweeping motion added to the moves, which swings the toolhead about the centre "
         "(+-sweeping_accel sweeping_period^2 / 32 mm) so it does not vibrate at one spot; 0 turns it off "
         "(default: 400 on Klipper, as its TEST_RESONANCES, lowered where the axis' speed, travel or acceleration "
         "needs it; 0 elsewhere, the only value accepted there)",
         ParamDomain::non_negative, kMaxAccelMmS2},
        {"sweeping_period", experiment_gcode::kKlipperSweepingPeriod_s, "s",
         "period of the sweeping motion; 0 turns it off", ParamDomain::non_negative, kMaxTimeS},
        {"center_mm", kMachineDefault, "mm", "position of the swept axis (default: middle of its travel)",
         ParamDomain::any, kMaxLengthMm},
        {"other_mm", kMachineDefault, "mm", "position of the other horizontal axis (default: middle)", ParamDomain::any,
         kMaxLengthMm},
        {"travel_speed_mm_s", kMachineDefault, "mm/s",
         "speed of the move to the start position (default: 100, or 90 % of the axes' limit when lower)",
         ParamDomain::positive, kMaxSpeedMmS},
        {"settle_s", 0.3, "s", "recorded rest before and after the sweep", ParamDomain::non_negative, kMaxTimeS},
        {"load_kg", 0, "kg",
         "bed slinger: a known mass placed on the bed for this sweep (the run says what to place and where, asks to "
         "confirm on a terminal, and records it; the simulated printer carries it); 0: the bed as it is",
         ParamDomain::non_negative, kMaxLoadKg},
        {"load_x_mm", kMachineDefault, "mm", "where the mass sits on the bed, x (default: middle of the travel)",
         ParamDomain::any, kMaxLengthMm},
        {"load_y_mm", kMachineDefault, "mm", "where the mass sits on the bed, y (default: middle of the travel)",
         ParamDomain::any, kMaxLengthMm}},
       {"accelerometer"},
       true});
  s.push_back({Protocol::axis_rectangle,
               "axis-rectangle",
               "the overshoot test of Hemminger, Improvements and Characterization of Error, Speed, and Capabilities "
               "in Low-Cost Additive Manufacturing Systems, UCLA, 2022: an XY rectangle with pauses at the corners, "
               "repeated; each axis sees step motions; the accelerometer is recorded (analyze: tunekit overshoot)",
               {{"width_mm", 40, "mm", "rectangle size along x", ParamDomain::positive, kMaxLengthMm},
                {"height_mm", 40, "mm", "rectangle size along y", ParamDomain::positive, kMaxLengthMm},
                {"speed_mm_s", kMachineDefault, "mm/s", "move speed (default: 100, or 90 % of the axes' limit)",
                 ParamDomain::positive, kMaxSpeedMmS},
                {"accel_mm_s2", kMachineDefault, "mm/s^2", "move acceleration (default: 3000, or the axes' limit)",
                 ParamDomain::positive, kMaxAccelMmS2},
                {"repeats", 5, "", "rectangles (Hemminger 2022: 5)", ParamDomain::count, 10000},
                {"pause_s", 0.3, "s", "pause at each corner", ParamDomain::positive, kMaxTimeS}},
               {"accelerometer"},
               false});
}

/// The one-layer test pattern (pads, lines, rings) in a coverage planner's order.
void add_pattern_spec(std::vector<ProtocolSpec>& s) {
  const ProtocolParam hotend = hotend_param();
  s.push_back(
      {Protocol::test_pattern,
       "test-pattern",
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
        {"travel_speed_mm_s", kMachineDefault, "mm/s", "travel speed (default: 150, or 90 % of the axes' limit)"},
        {"accel_mm_s2", kMachineDefault, "mm/s^2", "acceleration (default: 1500, or the axes' limit)"},
        {"z_mm", 0.2, "mm", "layer height / nozzle height"},
        {"zigzag", 0, "", "1: plain zigzag order instead of the coverage planner", ParamDomain::non_negative, 1},
        hotend},
       {},
       false});
}

/// The hot end's thermal experiment (thermal_plan.hpp).
void add_thermal_spec(std::vector<ProtocolSpec>& s) {
  s.push_back({Protocol::heater_identify,
               "heater-identify",
               "the hot end's thermal model in five minutes: from rest a heat-up to hotend_c, a step down and up, a "
               "full-fan step and an extrusion step, then a held-out fan and extrusion step the model predicts; the "
               "heater's temperature and duty recorded",
               {{"hotend_c", 210, "degC", "printing temperature held (never above the profile's hotend_max_c)",
                 ParamDomain::positive, kMaxTemperatureC},
                {"step_down_c", 15, "K", "the target's step down and back up", ParamDomain::positive, 100},
                {"fan_duty", 1, "", "the part-cooling fan's duty in the fan steps (0..1]", ParamDomain::positive, 1},
                {"feed_mm_s", kMachineDefault, "mm/s",
                 "filament feed of the extrusion steps (default: 4 mm^3/s, at most a third of the profile's "
                 "flow and feed limits)",
                 ParamDomain::positive, kMaxFeedMmS}},
               {"heater"},
               false});
}

std::vector<ProtocolSpec> make_specs() {
  std::vector<ProtocolSpec> s;
  add_liquefier_step_specs(s);
  add_liquefier_periodic_specs(s);
  add_print_specs(s);
  add_axis_specs(s);
  add_pattern_spec(s);
  add_thermal_spec(s);
  return s;
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

const ProtocolSpec& protocol_spec(Protocol id) {
  for (const auto& s : protocol_specs())
    if (s.id == id) return s;
  throw std::logic_error(fmt::format("protocol {} has no entry in the protocol table", static_cast<int>(id)));
}

const std::string& to_string(Protocol id) { return protocol_spec(id).name; }

}  // namespace tunekit::protocols
