#pragma once
// The calibration's experiments designed for the information they carry (the predicted intervals
// of experiment_information.hpp) rather than by habit, within a machine-time budget.
//
// What the Fisher information says about each experiment, and the design that follows:
//   axis sweep: near the mode, the information on the frequency and the damping ratio grows with
//     the square of the acceleration there and with the time the sweep spends in the mode's band,
//     1 / hz_per_sec. The acceleration keeps Klipper's shape, accel_per_hz f rising with f (the
//     shaper is scored against the measured spectrum, which carries that shape: held at the
//     axis' limit over the band instead, the simulated printer's X axis got a 29 Hz shaper for
//     its 48 Hz mode), with accel_per_hz as large as the axis' limit allows at the sweep's end;
//     the rate is kDesignedSweepRate_hz_s, 3 times Klipper's 2 Hz/s (on a printer whose limit
//     allows no more than Klipper's accel_per_hz, the intervals widen by sqrt(3)). At 7 Hz/s the
//     spectrum's fit, which starts the fit against the motion, found a mode near the sweep's
//     end on 3 of 60 drawn plants with strongly damped modes near 70 Hz.
//   flow sweep: a step's time constant and dead time are told by its transient, a few time
//     constants long; the gain by the steady holds. The hold is sized from the slowest time
//     constant the prior allows (its value at the lowest flow times kPriorTauMargin, the spread
//     of desktop liquefiers) with kHoldTaus of them: the transient, then steady force for the
//     gain. Half as many predict the same tau and b, but over drawn plants the whole-record
//     tau's interval then covered its truth on 88 % (docs/calibrate.md): the holds stay long,
//     and the sweep has kFlowLevels levels, one fewer than the protocol's default (tau's
//     information falls with the steps, 12 instead of 14).
//   chirp: the whole-record fit's information on tau grows with the number of corner periods the
//     chirp spends near the corner; kDesignedChirp_s holds dozens of them for any liquefier whose
//     corner lies above 2 Hz, and at least kChirpCornerPeriods (the protocol's own rule) otherwise.
// A budget (s of machine time for all experiments) scales the variable parts of all three (the
// sweeps' time, the holds, the chirp) by one factor; the intervals widen by about its inverse
// square root, which the predictions state before anything runs.

#include <map>
#include <string>

#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/experiment_information.hpp"

namespace tunekit::protocols {

inline constexpr double kDesignedSweepRate_hz_s = 6;  ///< the axis sweep's rate, Hz/s
inline constexpr double kMaxSweepRate_hz_s = 10;      ///< the fastest a budget may ask, Hz/s
inline constexpr double kPriorTauMargin = 3;          ///< slowest plausible tau over the prior's
inline constexpr double kHoldTaus = 20;               ///< flow-sweep hold, in slowest plausible taus
inline constexpr int kFlowLevels = 5;                 ///< flow-sweep levels (the protocol's default: 6)
inline constexpr double kMinHoldTaus = 3;             ///< the shortest hold a budget may ask
inline constexpr double kDesignedChirp_s = 10;        ///< chirp duration, s
inline constexpr double kChirpCornerPeriods = 20;     ///< at least this many corner periods

/// The designed parameters of calibrate's experiments at a time `scale` (1: the design; below
/// 1: the variable parts shortened by that factor for a budget), as protocol parameter overrides.
struct DesignedParams {
  std::map<std::string, double> params;
  std::string why;  ///< the design in one sentence
};

/// The axis sweep of `axis`: accel_per_hz reaching the axis' limit at the sweep's end (Klipper's
/// 60 where that is more), the rate kDesignedSweepRate_hz_s / scale (at most kMaxSweepRate_hz_s).
DesignedParams design_axis_sweep(const machine::MachineProfile& profile, const std::string& axis, double scale);

/// The flow sweep's hold from the prior's time constant at the lowest flow (the protocol's
/// default range: a tenth of 90 % of the hot end's flow limit), kHoldTaus x kPriorTauMargin of
/// them, times `scale` (at least kMinHoldTaus); kFlowLevels levels.
DesignedParams design_flow_sweep(const machine::MachineProfile& profile, const LiquefierPrior& prior, double scale);

/// The chirp's duration for an expected time constant (s): kDesignedChirp_s x scale, at least
/// kChirpCornerPeriods corner periods.
DesignedParams design_chirp(double expected_tau_s, double scale);

}  // namespace tunekit::protocols
