// The protocols' parameters derived from the machine's limits (machine_defaults.hpp).
#include "machine_defaults.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "tunekit/firmware/firmware_limits.hpp"

#include "sweep_moves.hpp"

namespace tunekit::protocols::experiment_gcode {
namespace {

// Margins under a limit for the defaults (the gate allows the limit itself): a default flow or
// speed stays 10 % below its limit, as the flow sweep's upper turning flow always has.
constexpr double kDefaultMargin = 0.9;
// The sweeping motion may take at most this share of the axis' acceleration limit: the rest is
// the pulses' (Klipper's own 400 mm/s^2 is 8 % of a 5000 mm/s^2 machine's).
constexpr double kMaxSweepingShare = 0.25;
// The lowest frequency range a sweep is designed for: a Marlin sweep whose highest reachable
// frequency falls below freq_start_hz + this is refused by the builder rather than shortened.
constexpr double kMinSweepSpan_hz = 10;

bool unset(const ExperimentRequest& r, const Experiment& e, const std::string& name) {
  return !r.overrides.count(name) && e.params.count(name) && std::isnan(e.params.at(name));
}

void set(Experiment& e, const std::string& name, double value, const std::string& why) {
  e.params[name] = value;
  e.excitation["machine_defaults"][name] = why;
}

void capped(const ExperimentRequest& r, Experiment& e, const std::string& name, double nominal, double limit,
            const std::string& what) {
  if (!unset(r, e, name)) return;
  set(e, name, std::min(nominal, limit),
      limit < nominal ? fmt::format("the {} {:g} (below {:g})", what, limit, nominal) : std::string("nominal"));
}

double axes_min(const machine::MachineProfile& p, double machine::AxisLimits::*field) {
  return std::min(p.axis("x").*field, p.axis("y").*field);
}

void feed_defaults(const ExperimentRequest& r, Experiment& e, double nominal_accel) {
  capped(r, e, "accel_mm_s2", nominal_accel, r.profile.extruder.max_accel_mm_s2, "extruder's max_accel_mm_s2");
}

/// The sine's and the chirp's feed levels and staircase step within the extruder's limits.
void staircase_defaults(const ExperimentRequest& r, Experiment& e) {
  feed_defaults(r, e, kNominalChirpAccel_mm_s2);
  const bool stops = r.dialect.firmware() == firmware::Firmware::klipper;
  const double cap = feed_cap_mm_s(r.profile) * kDefaultMargin / (stops ? 1 + kStaircasePeakExcess : 1.0);
  const double scale = std::min(1.0, cap / (kNominalFeedMean_mm_s + kNominalFeedAmplitude_mm_s));
  const std::string scaled =
      scale < 1 ? fmt::format(
                      "scaled by {:.3g} so that the highest feed stays within the extruder's and the hot "
                      "end's limits",
                      scale)
                : std::string("nominal");
  if (unset(r, e, "feed_mean_mm_s")) set(e, "feed_mean_mm_s", kNominalFeedMean_mm_s * scale, scaled);
  if (unset(r, e, "amplitude_mm_s")) set(e, "amplitude_mm_s", kNominalFeedAmplitude_mm_s * scale, scaled);
  if (unset(r, e, "segment_s")) {
    const double top = e.params.at("feed_mean_mm_s") + e.params.at("amplitude_mm_s");
    // The acceleration as written (whole mm/s^2, rounded down: experiment_gcode.cpp extruder_accel).
    const double a = stops ? std::floor(std::min(e.params.at("accel_mm_s2"), r.profile.extruder.max_accel_mm_s2)) : 0.0;
    const double keep = shortest_staircase_step_s(top, a, stops);
    double step = std::max(kNominalSegment_s, keep);
    std::string why = keep > kNominalSegment_s ? fmt::format(
                                                     "the shortest step the extruder keeps at {:.4g} mm/s and {:g} "
                                                     "mm/s^2 when it stops after every extrude-only move",
                                                     top, a)
                                               : std::string("nominal");
    // Where the stops take a noticeable share of each step, the longest step a chirp takes: each
    // stop leaves a ripple in the force at the step rate, which a load cell's samples alias into
    // the chirp's band (on the simulated Klipper printer with a 798 mm/s^2 extruder, 20 ms steps
    // read the frequency response's tau 0.053 s against the step test's 0.030 s; 50 ms steps 0.031 s).
    if (stops && 2 * top / (a * step) > kMaxStopShare && step < kLongestStaircaseStep_s) {
      step = kLongestStaircaseStep_s;
      why = fmt::format(
          "the longest step, so that fewer stops ripple the force: the extruder's ramps at {:g} mm/s^2 "
          "take more than {:g} % of a shorter one",
          a, 100 * kMaxStopShare);
    }
    set(e, "segment_s", step, why);
  }
  // The sine dwells hold at least 20 steps a period (experiments_liquefier.cpp).
  if (r.id == Protocol::liquefier_sine)
    capped(r, e, "freq_max_hz", kNominalSineMax_hz, 1.0 / (20 * e.params.at("segment_s")),
           "frequency whose period holds 20 staircase steps");
}

/// The pulses' largest speed amplitude (mm/s): a quarter period 1/(4f) at +-accel_per_hz f.
double pulse_speed_mm_s(const ExperimentRequest& r, const Experiment& e) {
  return (unset(r, e, "accel_per_hz") ? kKlipperAccelPerHz : e.params.at("accel_per_hz")) / 4;
}

/// Klipper's sweeping motion, lowered where the axis' speed, travel or acceleration needs it.
void sweeping_default(const ExperimentRequest& r, Experiment& e) {
  if (!unset(r, e, "sweeping_accel")) return;
  if (r.dialect.firmware() != firmware::Firmware::klipper) {
    set(e, "sweeping_accel", 0, "only Klipper's planner runs the sweeping motion");
    return;
  }
  const auto& ax = r.profile.axis(r.axis_in);
  const double period = e.params.at("sweeping_period");
  double s = kKlipperSweepingAccel_mm_s2;
  std::string why = "Klipper's TEST_RESONANCES default";
  const double by_accel = kMaxSweepingShare * ax.max_accel_mm_s2;
  if (period > 0) {
    const double v_pulse = pulse_speed_mm_s(r, e);
    const double by_speed = 4 * (kDefaultMargin * ax.max_velocity_mm_s - v_pulse) / period;
    const double centre = std::isnan(e.params.at("center_mm")) ? 0.5 * (ax.min_mm + ax.max_mm) : e.params["center_mm"];
    const double half = std::min(centre - ax.min_mm, ax.max_mm - centre);
    const double by_travel = 32 * kDefaultMargin * half / (period * period);
    for (const auto& [limit, what] :
         {std::pair{by_accel, "acceleration"}, std::pair{by_speed, "speed"}, std::pair{by_travel, "travel"}})
      if (limit < s) {
        s = std::max(0.0, limit);
        why = fmt::format("lowered from {:g} mm/s^2 to keep within the axis' {}", kKlipperSweepingAccel_mm_s2, what);
      }
  }
  set(e, "sweeping_accel", std::floor(s), why);
}

/// The sweep's end: Marlin's MIN_STEPS_PER_SEGMENT raises the acceleration of short half periods
/// (sweep_moves.hpp); the default end is the highest frequency the axis' limit still allows.
void sweep_end_default(const ExperimentRequest& r, Experiment& e) {
  if (!unset(r, e, "freq_end_hz")) return;
  const bool marlin =
      r.dialect.firmware() == firmware::Firmware::marlin || r.dialect.firmware() == firmware::Firmware::prusa;
  double end = kNominalSweepEnd_hz;
  std::string why = "nominal";
  if (marlin) {
    const double spm = r.axis_in == "x" ? r.profile.state.steps_per_mm_x : r.profile.state.steps_per_mm_y;
    const double min_half = firmware::limits::kMarlinMinStepsPerSegment / spm;
    const double cap = r.profile.axis(r.axis_in).max_accel_mm_s2 - e.params.at("sweeping_accel");
    // a half period 1/(2f) from rest to rest at +-a covers a / (16 f^2); it must cover 1.5 min_half.
    const double reach = std::floor(std::sqrt(cap / (24 * min_half)));
    if (reach < end && reach >= e.params.at("freq_start_hz") + kMinSweepSpan_hz) {
      end = reach;
      why = fmt::format(
          "Marlin joins moves of fewer than {} steps (MIN_STEPS_PER_SEGMENT): at {:g} steps/mm a half period above "
          "{:g} Hz needs more than the axis' {:g} mm/s^2",
          firmware::limits::kMarlinMinStepsPerSegment, spm, reach, cap);
    }
  }
  set(e, "freq_end_hz", end, why);
}

/// Klipper's accel_per_hz, lowered so that the pulses' acceleration accel_per_hz f reaches the
/// axis' limit (less the sweeping motion's) only at the sweep's end: the excitation keeps Klipper's
/// shape, rising with f, and so does the spectrum the shaper is scored against.
void accel_per_hz_default(const ExperimentRequest& r, Experiment& e) {
  if (!unset(r, e, "accel_per_hz")) return;
  const double cap = r.profile.axis(r.axis_in).max_accel_mm_s2 - e.params.at("sweeping_accel");
  const double most = cap / e.params.at("freq_end_hz");
  set(e, "accel_per_hz", std::min(kKlipperAccelPerHz, most),
      most < kKlipperAccelPerHz
          ? fmt::format("lowered from Klipper's {:g} so that the pulses reach the {:g} mm/s^2 the axis' limit leaves "
                        "them only at freq_end_hz {:g} Hz",
                        kKlipperAccelPerHz, cap, e.params.at("freq_end_hz"))
          : std::string("Klipper's default"));
}

/// The camera path's line test on a bed too short for its lines: every length and the speed
/// scaled together, so that the lines keep their durations (the photo's width at s is the
/// liquefier's response at t = s / v), and the lines placed above the travel's lower end.
void line_test_fit(const ExperimentRequest& r, Experiment& e) {
  constexpr const char* kLengths[] = {"rest_mm", "lead_mm", "step_mm", "tail_mm"};
  const auto& x = r.profile.axis("x");
  const auto& y = r.profile.axis("y");
  if (unset(r, e, "first_y_mm")) {
    const double lowest = y.min_mm + kLineClear_mm + (e.params.at("lines") - 1) * e.params.at("spacing_mm");
    const double nominal = 0.5 * (y.min_mm + y.max_mm) - kLineBelowMiddle_mm;
    set(e, "first_y_mm", std::max(nominal, lowest),
        nominal < lowest ? "raised so that every line lies on the bed" : "50 mm below the middle of the travel");
  }
  bool given = r.overrides.count("speed_mm_s") > 0;
  double need = 2 * kLineClear_mm;
  for (const char* k : kLengths) {
    given = given || r.overrides.count(k) > 0;
    need += e.params.at(k);
  }
  const double travel = x.max_mm - x.min_mm;
  if (given || need <= travel) return;
  const double scale = (travel - 2 * kLineClear_mm) / (need - 2 * kLineClear_mm);
  const std::string why = fmt::format(
      "scaled by {:.3g} with the speed, so that the lines fit the {:g} mm X travel and keep their durations", scale,
      travel);
  for (const char* k : kLengths) set(e, k, e.params.at(k) * scale, why);
  set(e, "speed_mm_s", e.params.at("speed_mm_s") * scale, why);
}

void motion_defaults(const ExperimentRequest& r, Experiment& e) {
  const auto& p = r.profile;
  const double accel = axes_min(p, &machine::AxisLimits::max_accel_mm_s2);
  const double speed = kDefaultMargin * axes_min(p, &machine::AxisLimits::max_velocity_mm_s);
  if (r.id == Protocol::axis_sweep) {
    capped(r, e, "travel_speed_mm_s", kNominalTravel_mm_s, speed, "axes' speed limit (90 %)");
    sweeping_default(r, e);
    sweep_end_default(r, e);
    accel_per_hz_default(r, e);
  } else if (r.id == Protocol::axis_rectangle) {
    capped(r, e, "speed_mm_s", 100, speed, "axes' speed limit (90 %)");
    capped(r, e, "accel_mm_s2", 3000, accel, "axes' acceleration limit");
  }
  if (r.id == Protocol::line_steps) line_test_fit(r, e);
  if (r.id == Protocol::ring_print || r.id == Protocol::line_steps || r.id == Protocol::test_pattern) {
    // Their retractions and primes are extrude-only moves at the print acceleration as the gate
    // reads it (Klipper caps them at max_extrude_only_accel by itself, Marlin and RepRapFirmware
    // at M204 R and M201 E, which these prints do not set): the extruder's limit applies too.
    const double print = std::min(accel, p.extruder.max_accel_mm_s2);
    const std::string what =
        print < accel ? "extruder's acceleration limit (its retractions and primes)" : "axes' acceleration limit";
    capped(r, e, "accel_mm_s2", r.id == Protocol::test_pattern ? 1500 : 1000, print, what);
    capped(r, e, "travel_speed_mm_s", 150, speed, "axes' speed limit (90 %)");
  }
}

/// The step test's two feeds within the extruder's and the hot end's limits.
void step_feed_defaults(const ExperimentRequest& r, Experiment& e) {
  const double cap = kDefaultMargin * feed_cap_mm_s(r.profile);
  capped(r, e, "feed_high_mm_s", kNominalStepHigh_mm_s, cap, "extruder's and hot end's feed limit (90 %)");
  capped(r, e, "feed_low_mm_s", kNominalStepLow_mm_s, e.params.at("feed_high_mm_s") / 3, "third of the high feed");
}

}  // namespace

double feed_cap_mm_s(const machine::MachineProfile& profile) {
  double cap = std::numeric_limits<double>::infinity();
  if (profile.extruder.max_velocity_mm_s > 0) cap = profile.extruder.max_velocity_mm_s;
  if (profile.extruder.max_flow_mm3_s > 0)
    cap = std::min(cap, profile.extruder.max_flow_mm3_s / profile.filament_area_mm2());
  return cap;
}

double shortest_staircase_step_s(double feed_mm_s, double accel_mm_s2, bool stops) {
  if (!stops) return 0;
  const double e = kStaircasePeakExcess;
  return (1 + e) * (1 + e) * feed_mm_s / (accel_mm_s2 * e);
}

void fill_machine_defaults(const ExperimentRequest& r, Experiment& e) {
  if (r.id == Protocol::liquefier_step) step_feed_defaults(r, e);
  if (r.id == Protocol::liquefier_step || r.id == Protocol::liquefier_flow_sweep)
    feed_defaults(r, e, kNominalStepAccel_mm_s2);
  else if (r.id == Protocol::liquefier_sine || r.id == Protocol::liquefier_chirp) staircase_defaults(r, e);
  else motion_defaults(r, e);
}

}  // namespace tunekit::protocols::experiment_gcode
