#pragma once
// The calibration's experiments designed for the information they carry (the predicted intervals
// of experiment_information.hpp) rather than by habit, within a machine-time budget.
//
// What the Fisher information says about each experiment, and the design that follows:
//   axis sweep: near the mode, the information on the frequency and the damping ratio grows with
//     the square of the acceleration there and with the time the sweep spends in the mode's band,
//     1 / hz_per_sec; away from it there is next to none. Each axis is swept twice (adaptive):
//     a coarse pass over the whole band at kCoarseSweepRate_hz_s, which locates the mode, and a
//     fine pass at kFineSweepRate_hz_s over the mode's band as the coarse pass found it, f (1 +-
//     w) with w = kFineBandZetas times its damping ratio (within kFineBandMin..kFineBandMax),
//     which the mode's reported interval comes from. The fine pass is designed, and its
//     intervals predicted, from the coarse pass' mode before it runs. The acceleration of both
//     keeps Klipper's shape, accel_per_hz f rising with f (the shaper is scored against the coarse
//     pass' spectrum, which carries that shape: held at the axis' limit over the band instead, the
//     simulated printer's X axis got a 29 Hz shaper for its 48 Hz mode), with accel_per_hz as
//     large as the axis' limit allows at the sweep's end (on an axis whose limit allows less than
//     Klipper's 60, the protocol's own default: as much as reaches the limit at the pass' end).
//     Safety: the fine pass' band lies inside the coarse pass' (FineSweepEnvelope), its widest
//     bands at both ends of that band are built and checked against the machine's limits with
//     the rest of the plan before anything is sent, and the pass that runs is built again and
//     checked by the same gate before it is sent.
//   flow sweep: a step's time constant and dead time are told by its transient, a few time
//     constants long; the gain by the steady holds. The hold is sized from the slowest time
//     constant the prior allows (its value at the lowest flow times kPriorTauMargin, the spread
//     of desktop liquefiers) with kHoldTaus of them: the transient, then steady force for the
//     gain. Half as many predict the same tau and b, but over drawn plants the whole-record
//     tau's interval then covered its truth on 88 % (docs/calibrate.md): the holds stay long,
//     and the sweep has kFlowLevels levels, one fewer than the protocol's default (tau's
//     information falls with the steps, 12 instead of 14). The dead time is told mostly by the
//     few samples just after each step (above all those inside the brief stop Klipper makes
//     between two extrude-only moves): with equal holds the steps fall at one or two phases of
//     the load cell's sample clock, and its interval varies by +-27 % with that phase (its
//     prediction is the average over phases, experiment_information.hpp). Holds staggered to
//     spread the phases made the interval follow the prediction (1.01-1.07) but covered the
//     truth on 88.5 % of 200 drawn plants: what the samples inside the stops tell is not to be
//     relied on, and the holds stay equal.
//   chirp: the whole-record fit's information on tau grows with the number of corner periods the
//     chirp spends near the corner; kDesignedChirp_s holds dozens of them for any liquefier whose
//     corner lies above 2 Hz, and at least kChirpCornerPeriods (the protocol's own rule) otherwise.
// A budget (s of machine time for all experiments) scales the variable parts of all three (the
// fine passes' time, the holds, the chirp) by one factor; the intervals widen by about its inverse
// square root, which the predictions state before anything runs.

#include <map>
#include <string>
#include <vector>

#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/experiment_information.hpp"

namespace tunekit::protocols {

inline constexpr double kCoarseSweepRate_hz_s = 10;  ///< the coarse pass' rate over the whole band, Hz/s
inline constexpr double kFineSweepRate_hz_s = 5;     ///< the fine pass' rate over the mode's band, Hz/s
inline constexpr double kMaxSweepRate_hz_s = 10;     ///< the fastest a budget may ask, Hz/s
inline constexpr double kFineBandZetas = 2.5;        ///< the fine band's half-width in damping ratios
inline constexpr double kFineBandMin = 0.1;          ///< ... at least this fraction of the frequency
inline constexpr double kFineBandMax = 0.35;         ///< ... at most this fraction
inline constexpr double kPriorTauMargin = 3;         ///< slowest plausible tau over the prior's
inline constexpr double kHoldTaus = 20;              ///< flow-sweep hold, in slowest plausible taus
inline constexpr int kFlowLevels = 5;                ///< flow-sweep levels (the protocol's default: 6)
inline constexpr double kMinHoldTaus = 3;            ///< the shortest hold a budget may ask
inline constexpr double kDesignedChirp_s = 10;       ///< chirp duration, s
inline constexpr double kChirpCornerPeriods = 20;    ///< at least this many corner periods

/// The designed parameters of calibrate's experiments at a time `scale` (1: the design; below
/// 1: the variable parts shortened by that factor for a budget), as protocol parameter overrides.
struct DesignedParams {
  std::map<std::string, double> params;
  std::string why;  ///< the design in one sentence
};

/// The coarse pass of `axis` over the protocol's whole band: accel_per_hz reaching the axis' limit
/// at the sweep's end (Klipper's 60 where that is more), kCoarseSweepRate_hz_s.
DesignedParams design_axis_sweep(const machine::MachineProfile& profile, const std::string& axis, double scale);

/// The band a fine pass may sweep: the coarse pass' band as built (Hz).
struct FineSweepEnvelope {
  double freq_start_hz = 0, freq_end_hz = 0;
};

/// The fine pass of `axis` over the band of the mode `mode` (its freq_hz and zeta: the coarse
/// pass' estimate, or the prior's in the plan): f (1 +- w), w = kFineBandZetas zeta within
/// kFineBandMin..kFineBandMax, moved (and if need be cut) to lie inside `envelope`; the rate
/// kFineSweepRate_hz_s / scale (at most kMaxSweepRate_hz_s) and the coarse pass' designed
/// accel_per_hz (none where the axis' limit allows less than Klipper's: the protocol's default).
DesignedParams design_axis_fine_sweep(const machine::MachineProfile& profile, const std::string& axis,
                                      const AxisPrior& mode, const FineSweepEnvelope& envelope, double scale);

/// The fine passes that span the envelope's extremes: the widest band a mode at either end of
/// it may ask (the plan builds and checks both before anything is sent).
std::vector<AxisPrior> fine_sweep_extremes(const FineSweepEnvelope& envelope);

/// The flow sweep's hold from the prior's time constant at the lowest flow (the protocol's
/// default range: a tenth of 90 % of the hot end's flow limit), kHoldTaus x kPriorTauMargin of
/// them, times `scale` (at least kMinHoldTaus); kFlowLevels levels.
DesignedParams design_flow_sweep(const machine::MachineProfile& profile, const LiquefierPrior& prior, double scale);

/// The chirp's duration for an expected time constant (s): kDesignedChirp_s x scale, at least
/// kChirpCornerPeriods corner periods.
DesignedParams design_chirp(double expected_tau_s, double scale);

}  // namespace tunekit::protocols
