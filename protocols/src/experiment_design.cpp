// calibrate's experiments designed for their information (experiment_design.hpp).
#include "tunekit/protocols/experiment_design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

#include "sweep_moves.hpp"

namespace tunekit::protocols {
namespace {

// The sweep's nominal end (Hz) and Klipper's accel_per_hz (mm/s^2 per Hz), the protocol's defaults.
constexpr double kSweepEnd_hz = 100;
constexpr double kKlipperAccelPerHz_mm_s2 = 60;

void check_scale(double scale) {
  if (!(scale > 0 && scale <= 1))
    throw InputError(fmt::format("the experiments' time scale must lie in (0, 1], not {:g}", scale));
}

}  // namespace

DesignedParams design_axis_sweep(const machine::MachineProfile& profile, const std::string& axis, double scale) {
  check_scale(scale);
  const auto& limits = profile.axis(axis);
  DesignedParams d;
  // accel_per_hz f reaches the axis' limit (less Klipper's sweeping motion) at the sweep's end:
  // the most acceleration at every frequency that keeps the excitation's shape.
  const double per_hz =
      std::floor((limits.max_accel_mm_s2 - experiment_gcode::kKlipperSweepingAccel_mm_s2) / kSweepEnd_hz);
  const double rate = std::min(kMaxSweepRate_hz_s, kDesignedSweepRate_hz_s / scale);
  d.params["hz_per_sec"] = rate;
  if (per_hz > kKlipperAccelPerHz_mm_s2) {
    d.params["accel_per_hz"] = per_hz;
    d.why = fmt::format("accel_per_hz {:g} (the axis' {:g} mm/s^2 at {:g} Hz), swept at {:.3g} Hz/s", per_hz,
                        limits.max_accel_mm_s2, kSweepEnd_hz, rate);
  } else {
    d.why = fmt::format("swept at {:.3g} Hz/s", rate);
  }
  return d;
}

DesignedParams design_flow_sweep(const machine::MachineProfile& profile, const LiquefierPrior& prior, double scale) {
  check_scale(scale);
  const double area = profile.filament_area_mm2();
  double limit = std::numeric_limits<double>::infinity();
  if (profile.extruder.max_flow_mm3_s > 0) limit = profile.extruder.max_flow_mm3_s;
  if (profile.extruder.max_velocity_mm_s > 0) limit = std::min(limit, profile.extruder.max_velocity_mm_s * area);
  DesignedParams d;
  if (!std::isfinite(limit)) return d;  // the protocol refuses it and says why
  const double lowest_feed = 0.09 * limit / area;
  const double tau = prior.tau_ref_s * std::pow(lowest_feed / prior.ref_feed_mm_s, prior.b);
  const double slowest = kPriorTauMargin * tau;
  const double taus = std::max(kMinHoldTaus, kHoldTaus * scale);
  d.params["expected_tau_s"] = slowest;
  d.params["hold_taus"] = taus;
  d.params["levels"] = kFlowLevels;
  d.why = fmt::format(
      "{} levels held {:.3g} s each: {:.3g} of the slowest time constant expected at the lowest flow ({:.3g} s, "
      "{:g} times the prior's {:.3g} s)",
      kFlowLevels, taus * slowest, taus, slowest, kPriorTauMargin, tau);
  return d;
}

DesignedParams design_chirp(double expected_tau_s, double scale) {
  check_scale(scale);
  const double corner_period = 2 * std::numbers::pi * expected_tau_s;
  DesignedParams d;
  d.params["duration_s"] = std::max(kDesignedChirp_s * scale, kChirpCornerPeriods * corner_period);
  d.why = fmt::format("{:.3g} s: {:.3g} corner periods of tau {:.3g} s", d.params["duration_s"],
                      d.params["duration_s"] / corner_period, expected_tau_s);
  return d;
}

}  // namespace tunekit::protocols
