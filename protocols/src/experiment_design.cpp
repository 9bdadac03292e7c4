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

namespace {

/// accel_per_hz f reaching the axis' limit (less Klipper's sweeping motion) at the sweep's end:
/// the most acceleration at every frequency that keeps the excitation's shape; 0 where Klipper's
/// default is more than that limit allows (the protocol then lowers it itself).
double designed_accel_per_hz(const machine::MachineProfile& profile, const std::string& axis) {
  const double per_hz =
      std::floor((profile.axis(axis).max_accel_mm_s2 - experiment_gcode::kKlipperSweepingAccel_mm_s2) / kSweepEnd_hz);
  return per_hz > kKlipperAccelPerHz_mm_s2 ? per_hz : 0.0;
}

/// The rate of the fine pass at `scale`, Hz/s.
double fine_rate(double scale) { return std::min(kMaxSweepRate_hz_s, kFineSweepRate_hz_s / scale); }

}  // namespace

DesignedParams design_axis_sweep(const machine::MachineProfile& profile, const std::string& axis, double scale) {
  check_scale(scale);
  DesignedParams d;
  d.params["hz_per_sec"] = kCoarseSweepRate_hz_s;
  const double per_hz = designed_accel_per_hz(profile, axis);
  if (per_hz > 0) d.params["accel_per_hz"] = per_hz;
  d.why = fmt::format("coarse pass over the whole band at {:g} Hz/s{}: it locates the mode the fine pass sweeps",
                      kCoarseSweepRate_hz_s,
                      per_hz > 0 ? fmt::format(", accel_per_hz {:g} (the axis' {:g} mm/s^2 at {:g} Hz)", per_hz,
                                               profile.axis(axis).max_accel_mm_s2, kSweepEnd_hz)
                                 : std::string());
  return d;
}

DesignedParams design_axis_fine_sweep(const machine::MachineProfile& profile, const std::string& axis,
                                      const AxisPrior& mode, const FineSweepEnvelope& envelope, double scale) {
  check_scale(scale);
  if (!(envelope.freq_end_hz > envelope.freq_start_hz && envelope.freq_start_hz > 0))
    throw InputError(
        fmt::format("the fine pass' envelope {:g}-{:g} Hz is empty", envelope.freq_start_hz, envelope.freq_end_hz));
  const double f = std::clamp(mode.freq_hz, envelope.freq_start_hz, envelope.freq_end_hz);
  const double w = std::clamp(kFineBandZetas * mode.zeta, kFineBandMin, kFineBandMax);
  const double width = std::min(2 * w * f, envelope.freq_end_hz - envelope.freq_start_hz);
  // Centred on the mode, moved inside the envelope where it would reach past an end.
  const double lo = std::clamp(f - width / 2, envelope.freq_start_hz, envelope.freq_end_hz - width);
  DesignedParams d;
  d.params["freq_start_hz"] = lo;
  d.params["freq_end_hz"] = lo + width;
  d.params["hz_per_sec"] = fine_rate(scale);
  if (const double per_hz = designed_accel_per_hz(profile, axis); per_hz > 0) d.params["accel_per_hz"] = per_hz;
  d.why = fmt::format(
      "fine pass over {:.4g}-{:.4g} Hz at {:.3g} Hz/s: the mode at {:.4g} Hz +- {:g} times its damping ratio {:.3g}",
      lo, lo + width, fine_rate(scale), mode.freq_hz, kFineBandZetas, mode.zeta);
  return d;
}

std::vector<AxisPrior> fine_sweep_extremes(const FineSweepEnvelope& envelope) {
  AxisPrior low, high;
  low.freq_hz = envelope.freq_start_hz;
  high.freq_hz = envelope.freq_end_hz;
  low.zeta = high.zeta = kFineBandMax / kFineBandZetas;
  return {low, high};
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
      "{} levels held {:.3g} s each : {:.3g} of the slowest time "
      "constant expected at the lowest flow ({:.3g} s, "
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
