#pragma once
// A synthetic flow sweep (the liquefier-flow-sweep protocol's level order) whose every step is
// exactly first order plus dead time with tau = a Q^b at the level it arrives at, rising and
// falling alike: y(t) = y0 + sum_j K dQ_j (1 - exp(-(t - t_j - theta) / tau(Q_j after))).
// Shared by the flow-level tests and the analysis benchmark.

#include <cmath>
#include <random>
#include <vector>

#include "tunekit/protocols/flow_sweep_plan.hpp"

namespace tunekit::test {

struct SynthFlowSweep {
  std::vector<double> t, u, y;  ///< s, mm^3/s, N
  std::vector<double> measured_flows;
  std::vector<double> turning_flows;
};

struct SynthFlowSweepTruth {
  double a = 0.7, b = -0.5;  ///< tau_s = a Q^b
  double K = 0.8, theta_s = 0.04, y0 = 0.5;
  double noise = 0.002;  ///< output noise standard deviation
  double rate_hz = 1000;
  double tau(double q) const { return a * std::pow(q, b); }
};

inline SynthFlowSweep synth_flow_sweep(const SynthFlowSweepTruth& tr, int levels, double flow_min, double flow_max,
                                       double hold_s, double settle_s, unsigned seed = 7) {
  const auto plan = protocols::plan_flow_sweep(flow_min, flow_max, levels, 1, hold_s, 1.0, settle_s);
  SynthFlowSweep s;
  s.measured_flows = plan.measured_flows_mm3_s;
  s.turning_flows = {plan.flow_min_mm3_s, plan.flow_max_mm3_s};
  struct Step {
    double t, dq, tau;
  };
  std::vector<Step> steps;
  for (std::size_t i = 1; i < plan.sequence_mm3_s.size(); ++i)
    steps.push_back({settle_s + static_cast<double>(i - 1) * hold_s,
                     plan.sequence_mm3_s[i] - plan.sequence_mm3_s[i - 1], tr.tau(plan.sequence_mm3_s[i])});
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, tr.noise);
  const double end = plan.duration_s();
  const auto n = static_cast<std::size_t>(end * tr.rate_hz);
  s.t.reserve(n);
  s.u.reserve(n);
  s.y.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Sample instants offset by half a sample from the step times: the midpoint rule is exact.
    const double t = (static_cast<double>(i) + 0.5) / tr.rate_hz;
    double u = plan.sequence_mm3_s.front(), y = tr.y0 + tr.K * u;
    for (const auto& st : steps) {
      if (t >= st.t) u += st.dq;
      const double age = t - st.t - tr.theta_s;
      if (age > 0) y += tr.K * st.dq * (1 - std::exp(-age / st.tau));
    }
    s.t.push_back(t);
    s.u.push_back(u);
    s.y.push_back(y + noise(rng));
  }
  return s;
}

}  // namespace tunekit::test
