// The operating points, steps grouped by the level they arrive at: per-level K, tau, theta, the
// rising-minus-falling difference of tau, the level trends, and the whiteness check of pooled
// fits (step_analysis.hpp).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/fitting/margins.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::ident {
namespace {

using fitting::FitResult;
using fitting::StepRecord;

// One fit over the given steps: the step's own fit for one, else pooled.
FitResult fit_arrivals(const StepAnalysis& a, const std::vector<StepRecord>& recs, const std::vector<std::size_t>& idx,
                       const StepAnalysisOptions& o) {
  if (idx.size() == 1) return *a.steps[idx.front()].fit;
  std::vector<StepRecord> sub;
  for (std::size_t i : idx) sub.push_back(recs[i]);
  return fitting::fit_steps_pooled(sub, o.model, &*a.steps[idx.front()].fit);
}

// theta_s = c0 + c1 u by least squares, with intervals from three levels on.
FitResult fit_theta_line(const std::vector<double>& u, const std::vector<double>& theta, const std::string& uunit) {
  double mu = 0, mt = 0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    mu += u[i];
    mt += theta[i];
  }
  mu /= static_cast<double>(u.size());
  mt /= static_cast<double>(u.size());
  double suu = 0, sut = 0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    suu += (u[i] - mu) * (u[i] - mu);
    sut += (u[i] - mu) * (theta[i] - mt);
  }
  if (!(suu > 0)) throw InputError("theta trend: all levels are at the same input");
  const double c1 = sut / suu, c0 = mt - c1 * mu;
  fitting::LsqProblem prob;
  prob.params = {{"c0", "s", c0}, {"c1", "s/(" + uunit + ")", c1}};
  prob.num_residuals = static_cast<int>(u.size());
  prob.observed = theta;
  prob.residuals_are_time_ordered = false;
  prob.residuals_and_jacobian = [u, theta](const double* p, double* r, double* jac) {
    for (std::size_t i = 0; i < u.size(); ++i) {
      r[i] = p[0] + p[1] * u[i] - theta[i];
      if (jac != nullptr) {
        jac[2 * i] = 1;
        jac[2 * i + 1] = u[i];
      }
    }
    return true;
  };
  fitting::LsqOptions opt;
  opt.compute_covariance = u.size() > 2;
  auto f = fitting::solve_least_squares("line: theta_s = c0 + c1 * u", prob, opt);
  if (u.size() == 2) f.warnings.push_back("two levels: the line passes through both; no uncertainty");
  return f;
}

void fit_level_trends(StepAnalysis& a, const StepAnalysisOptions& o) {
  std::vector<const ArrivalLevel*> both, all;
  for (const auto& l : a.arrival_levels) {
    if (!(l.u > 0)) continue;
    all.push_back(&l);
    if (l.n_rising > 0 && l.n_falling > 0) both.push_back(&l);
  }
  a.level_trends.both_directions_only = both.size() >= 3;
  const auto& use = a.level_trends.both_directions_only ? both : all;
  if (use.size() < 2) return;
  std::vector<double> u, tau, K, theta;
  for (const auto* l : use) {
    u.push_back(l->u);
    tau.push_back(l->fit.value("tau_s"));
    K.push_back(l->fit.value("K"));
    theta.push_back(l->fit.value("theta_s"));
  }
  auto attempt = [&](const char* what, auto&& fit) -> std::optional<FitResult> {
    try {
      return fit();
    } catch (const Error& e) {
      a.warnings.push_back(fmt::format("arrival-level trend of {}: {}", what, e.message()));
      return std::nullopt;
    }
  };
  if (std::all_of(tau.begin(), tau.end(), [](double v) { return v > 0; }))
    a.level_trends.tau = attempt("tau", [&] { return fit_power_law(u, tau, "tau_s", o.input_unit, "s"); });
  if (std::all_of(K.begin(), K.end(), [](double v) { return v > 0; }))
    a.level_trends.K = attempt("K", [&] { return fit_power_law(u, K, "K", o.input_unit, o.gain_unit); });
  if (!use.front()->fit.param("theta_s").fixed)  // the first-order model holds theta at 0
    a.level_trends.theta = attempt("theta", [&] { return fit_theta_line(u, theta, o.input_unit); });
}

nlohmann::json flow_level_ci95(const fitting::Param& p) { return nlohmann::json::array({p.ci95_lo, p.ci95_hi}); }

// NaN as null (JSON has no NaN).
nlohmann::json flow_level_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

}  // namespace

std::string pooled_whiteness_warning(const FitResult& pooled, const std::vector<const FitResult*>& members,
                                     const std::string& what) {
  const double p = pooled.diagnostics.whiteness_p;
  if (members.size() < 2 || !(p < kWhitenessAlarmP)) return {};
  std::size_t white = 0, tested = 0;
  for (const auto* m : members) {
    if (!std::isfinite(m->diagnostics.whiteness_p)) continue;
    ++tested;
    if (m->diagnostics.whiteness_p >= kWhitenessAlarmP) ++white;
  }
  if (tested < 2 || 4 * white < 3 * tested) return {};
  // A difference between the steps matters only when one step's K or tau differs from the
  // pooled value beyond the equivalence margin (its own 95 % interval wholly outside it): on
  // precise data a plant with one K and tau still fails the whiteness test over tiny offsets.
  auto find = [](const FitResult& f, const std::string& name) -> const fitting::Param* {
    for (const auto& p : f.params)
      if (p.name == name) return &p;
    return nullptr;
  };
  bool beyond = false;
  for (const auto* m : members)
    for (const char* name : {"K", "tau_s"}) {
      const auto *q = find(*m, name), *qp = find(pooled, name);
      if (q == nullptr || qp == nullptr || !std::isfinite(q->std_error)) continue;
      const double margin = fitting::equivalence_margin(name).relative * std::abs(qp->value);
      if (fitting::beyond_margin(q->value - qp->value, fitting::kZ95 * q->std_error, margin) > 0) beyond = true;
    }
  if (!beyond) return {};
  return fmt::format(
      "{}: its residuals are not white (Ljung-Box p = {:.2g}) while {} of the {} single-step fits' "
      "are: the steps {} (the dynamics change with the level; see the arrival levels and their trend)",
      what, p, white, tested, kDoNotShareDynamics);
}

void analyze_arrival_levels(StepAnalysis& a, const std::vector<StepRecord>& recs, const StepAnalysisOptions& o) {
  a.input_unit = o.input_unit;
  double umax = 0;
  for (const auto& s : a.steps) umax = std::max(umax, std::abs(s.step.u_after));
  // Levels within 2 % of each other are one (relative to the level: a sweep's levels are
  // spaced geometrically), with a floor of 0.1 % of the largest for levels near zero.
  auto same = [abs_floor = 1e-3 * std::max(umax, 1e-300)](double x, double y) {
    return std::abs(x - y) <= std::max(0.02 * std::max(std::abs(x), std::abs(y)), abs_floor);
  };
  struct Group {
    double sum = 0;
    std::vector<std::size_t> idx;
    double level() const { return sum / static_cast<double>(idx.size()); }
  };
  std::vector<Group> groups;
  for (std::size_t i = 0; i < a.steps.size(); ++i) {
    if (!a.steps[i].fit) continue;
    const double u = a.steps[i].step.u_after;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const Group& g) { return same(g.level(), u); });
    if (it == groups.end()) groups.push_back({u, {i}});
    else {
      it->sum += u;
      it->idx.push_back(i);
    }
  }
  std::sort(groups.begin(), groups.end(), [](const Group& x, const Group& y) { return x.level() < y.level(); });
  std::string not_white;
  for (const auto& g : groups) {
    ArrivalLevel l;
    l.u = g.level();
    l.steps = g.idx;
    std::vector<std::size_t> up, down;
    for (std::size_t i : g.idx) (a.steps[i].step.rising() ? up : down).push_back(i);
    l.n_rising = static_cast<int>(up.size());
    l.n_falling = static_cast<int>(down.size());
    try {
      l.fit = fit_arrivals(a, recs, g.idx, o);
    } catch (const Error& e) {
      a.warnings.push_back(fmt::format("arrival level u = {:.6g}: {}", l.u, e.message()));
      continue;
    }
    if (!up.empty() && !down.empty()) {
      try {
        const FitResult fu = fit_arrivals(a, recs, up, o), fd = fit_arrivals(a, recs, down, o);
        const auto &tu = fu.param("tau_s"), &td = fd.param("tau_s");
        l.rising_minus_falling_tau_s = tu.value - td.value;
        const double se = std::hypot(tu.std_error, td.std_error);
        if (std::isfinite(se)) {
          const double half = fitting::t_multiplier(0.95, 0) * se;  // normal quantile
          l.rmf_ci95_lo = l.rising_minus_falling_tau_s - half;
          l.rmf_ci95_hi = l.rising_minus_falling_tau_s + half;
        }
      } catch (const Error& e) {
        a.warnings.push_back(fmt::format("arrival level u = {:.6g}, rising against falling: {}", l.u, e.message()));
      }
    }
    if (g.idx.size() > 1) {
      std::vector<const FitResult*> members;
      for (std::size_t i : g.idx) members.push_back(&*a.steps[i].fit);
      if (!pooled_whiteness_warning(l.fit, members, "").empty())
        not_white += fmt::format("{}{:.6g}", not_white.empty() ? "" : ", ", l.u);
    }
    a.arrival_levels.push_back(std::move(l));
  }
  // One warning for all levels whose pooled fit is not white while their single-step fits are.
  if (!not_white.empty())
    a.warnings.push_back(
        fmt::format("arrival levels u = {}: the pooled fit's residuals are not white (Ljung-Box p < "
                    "{:g}) while the single-step fits' are: the rising and falling arrivals {} (see "
                    "rising_minus_falling_tau_s)",
                    not_white, kWhitenessAlarmP, kDoNotShareDynamics));
  fit_level_trends(a, o);
}

nlohmann::json arrival_levels_json(const StepAnalysis& a) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& l : a.arrival_levels) {
    const auto &K = l.fit.param("K"), &tau = l.fit.param("tau_s"), &theta = l.fit.param("theta_s");
    nlohmann::json steps = nlohmann::json::array();
    for (std::size_t i : l.steps) steps.push_back(a.steps[i].step.index);
    out.push_back({{"u", l.u},
                   {"unit", a.input_unit},
                   {"n_steps", l.steps.size()},
                   {"n_rising", l.n_rising},
                   {"n_falling", l.n_falling},
                   {"steps", steps},
                   {"tau_s", tau.value},
                   {"tau_ci95", flow_level_ci95(tau)},
                   {"K", K.value},
                   {"K_ci95", flow_level_ci95(K)},
                   {"theta_s", theta.value},
                   {"theta_ci95", flow_level_ci95(theta)},
                   {"stderr", {{"K", K.std_error}, {"tau_s", tau.std_error}, {"theta_s", theta.std_error}}},
                   {"rising_minus_falling_tau_s", flow_level_number(l.rising_minus_falling_tau_s)},
                   {"rising_minus_falling_tau_ci95", std::isfinite(l.rmf_ci95_lo)
                                                         ? nlohmann::json::array({l.rmf_ci95_lo, l.rmf_ci95_hi})
                                                         : nlohmann::json(nullptr)},
                   {"directions_differ",
                    std::isfinite(l.rmf_ci95_lo) ? nlohmann::json(l.directions_differ()) : nlohmann::json(nullptr)},
                   {"fit", fitting::to_json(l.fit)}});
  }
  return out;
}

nlohmann::json level_trends_json(const StepAnalysis& a) {
  nlohmann::json out = nlohmann::json::object();
  const auto& t = a.level_trends;
  auto power = [](const FitResult& f) {
    const auto &pa = f.param("a"), &pb = f.param("b");
    return nlohmann::json{{"a", pa.value},
                          {"a_ci95", flow_level_ci95(pa)},
                          {"b", pb.value},
                          {"b_ci95", flow_level_ci95(pb)},
                          {"fit", fitting::to_json(f)}};
  };
  if (t.tau) out["tau_s"] = power(*t.tau);
  if (t.K) out["K"] = power(*t.K);
  if (t.theta) {
    const auto &c0 = t.theta->param("c0"), &c1 = t.theta->param("c1");
    out["theta_s"] = {{"c0", c0.value},
                      {"c0_ci95", flow_level_ci95(c0)},
                      {"c1", c1.value},
                      {"c1_ci95", flow_level_ci95(c1)},
                      {"fit", fitting::to_json(*t.theta)}};
  }
  out["levels_used"] = t.both_directions_only ? "levels reached from both directions" : "every arrival level";
  out["unit"] = a.input_unit;
  return out;
}

}  // namespace tunekit::ident
