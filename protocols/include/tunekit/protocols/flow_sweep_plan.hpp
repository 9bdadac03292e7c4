#pragma once
// The liquefier flow sweep: feed steps up and down through several flow levels of the hot end's
// range, so that every level is reached once from below and once from above.
//
// The liquefier is not linear time-invariant: its time constant falls as the flow rises (Holtrup,
// Tuning liquefier dynamics, MSc thesis, University of Twente, 2019, Table 4.3). A step settles
// into the dynamics of the level it ARRIVES at, so each measured level is approached from both
// sides: a rising step (from the level below) and a falling step (from the level above). Their
// fitted time constants bracket the level's own (a larger step sees more of the neighbour's
// dynamics) and their difference tells whether the first-order model holds there.
//
// Levels: `levels` measured flows spaced geometrically strictly between a lower turning flow
// flow_min and an upper turning flow flow_max:
//   q_i = flow_min * r^i,  i = 1..levels,  r = (flow_max / flow_min)^(1 / (levels + 1)).
// One cycle: flow_min -> q_1 -> ... -> q_levels -> flow_max -> q_levels -> ... -> q_1 -> flow_min,
// 2 (levels + 1) steps. The turning flows are reached from one side only. Every level is held
// hold_taus * expected_tau_s, the expected time constant at the lowest flow (the slowest).

#include <vector>

namespace tunekit::protocols {

struct FlowSweepPlan {
  std::vector<double> measured_flows_mm3_s;  ///< q_1 .. q_levels, rising
  double flow_min_mm3_s = 0;                 ///< lower turning flow (start and end)
  double flow_max_mm3_s = 0;                 ///< upper turning flow
  double ratio = 0;                          ///< r, flow ratio between neighbouring levels
  double hold_s = 0;                         ///< time at each level, s
  double settle_s = 0;                       ///< time at flow_min before the first step, s
  /// The flows in the order they are run, the first being the settle at flow_min
  /// (settle_s), every later one held hold_s.
  std::vector<double> sequence_mm3_s;
  double duration_s() const;  ///< settle_s + (steps) * hold_s
  int steps() const { return static_cast<int>(sequence_mm3_s.size()) - 1; }
};

/// Plans the sweep. Throws InputError unless 0 < flow_min < flow_max, levels >= 1, cycles >= 1,
/// and the times are positive and finite.
FlowSweepPlan plan_flow_sweep(double flow_min_mm3_s, double flow_max_mm3_s, int levels, int cycles,
                              double expected_tau_s, double hold_taus, double settle_s);

}  // namespace tunekit::protocols
