#include "tunekit/protocols/flow_sweep_plan.hpp"

#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::protocols {

double FlowSweepPlan::duration_s() const { return settle_s + steps() * hold_s; }

FlowSweepPlan plan_flow_sweep(double flow_min, double flow_max, int levels, int cycles, double expected_tau_s,
                              double hold_taus, double settle_s) {
  if (!(std::isfinite(flow_min) && std::isfinite(flow_max) && flow_min > 0 && flow_max > flow_min))
    throw InputError(
        fmt::format("flow sweep: the lowest flow ({:g} mm^3/s) must be positive and below the highest "
                    "({:g} mm^3/s)",
                    flow_min, flow_max));
  if (levels < 1 || cycles < 1) throw InputError("flow sweep: levels and cycles must be at least 1");
  if (!(std::isfinite(expected_tau_s) && expected_tau_s > 0 && std::isfinite(hold_taus) && hold_taus > 0 &&
        std::isfinite(settle_s) && settle_s > 0))
    throw InputError("flow sweep: expected_tau_s, hold_taus and settle_s must be positive and finite");
  FlowSweepPlan p;
  p.flow_min_mm3_s = flow_min;
  p.flow_max_mm3_s = flow_max;
  p.ratio = std::pow(flow_max / flow_min, 1.0 / (levels + 1));
  p.hold_s = hold_taus * expected_tau_s;
  p.settle_s = settle_s;
  for (int i = 1; i <= levels; ++i) p.measured_flows_mm3_s.push_back(flow_min * std::pow(p.ratio, i));
  p.sequence_mm3_s.push_back(flow_min);
  for (int c = 0; c < cycles; ++c) {
    for (double q : p.measured_flows_mm3_s) p.sequence_mm3_s.push_back(q);
    p.sequence_mm3_s.push_back(flow_max);
    for (auto it = p.measured_flows_mm3_s.rbegin(); it != p.measured_flows_mm3_s.rend(); ++it)
      p.sequence_mm3_s.push_back(*it);
    p.sequence_mm3_s.push_back(flow_min);
  }
  return p;
}

}  // namespace tunekit::protocols
