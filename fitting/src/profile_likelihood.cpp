#include "tunekit/fitting/profile_likelihood.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::fitting {
namespace {

// The profile of one parameter: S(v) by warm-started solves, remembering every point solved.
class PlProfile {
 public:
  PlProfile(const LsqProblem& problem, const FitResult& fit, int index, const ProfileOptions& o)
      : prob_(problem), j_(static_cast<std::size_t>(index)) {
    for (const auto& p : fit.params) best_.push_back(p.value);
    inner_.compute_covariance = false;
    inner_.require_convergence = false;
    inner_.max_iterations = o.inner_max_iterations;
    inner_.function_tolerance = 1e-12;
    inner_.parameter_tolerance = 1e-10;
    inner_.gradient_tolerance = 1e-12;
    prob_.params[j_].fixed = true;
    prob_.params[j_].lower = -HUGE_VAL;
    prob_.params[j_].upper = HUGE_VAL;
    prob_.residuals_are_time_ordered = false;
    solved_[best_[j_]] = {fit.diagnostics.rss, best_};
  }

  // S(v); +inf where the model cannot be fitted with p_j = v (outside its domain).
  double rss(double v) {
    if (auto it = solved_.find(v); it != solved_.end()) return it->second.first;
    // Warm start from the nearest point already solved.
    auto it = solved_.lower_bound(v);
    if (it == solved_.end() || (it != solved_.begin() && std::abs(std::prev(it)->first - v) < std::abs(it->first - v)))
      --it;
    const auto& start = it->second.second;
    for (std::size_t q = 0; q < prob_.params.size(); ++q) prob_.params[q].start = start[q];
    prob_.params[j_].start = v;
    ++solves_;
    double s = HUGE_VAL;
    std::vector<double> x = start;
    try {
      const auto r = solve_least_squares("profile", prob_, inner_);
      for (std::size_t q = 0; q < r.params.size(); ++q) x[q] = r.params[q].value;
      if (std::isfinite(r.diagnostics.rss)) s = r.diagnostics.rss;
    } catch (const Error&) {
      s = HUGE_VAL;
    }
    x[j_] = v;
    solved_[v] = {s, x};
    return s;
  }
  int solves() const { return solves_; }

 private:
  LsqProblem prob_;
  std::size_t j_;
  LsqOptions inner_;
  std::vector<double> best_;
  std::map<double, std::pair<double, std::vector<double>>> solved_;
  int solves_ = 0;
};

struct PlSetup {
  double rss_min, s2, threshold, half_width;
};

PlSetup pl_setup(const LsqProblem& problem, const FitResult& fit, int index, const ProfileOptions& o) {
  if (index < 0 || static_cast<std::size_t>(index) >= fit.params.size() ||
      problem.params[static_cast<std::size_t>(index)].fixed)
    throw InputError("profile likelihood: parameter " + std::to_string(index) + " is not a free parameter");
  const auto& p = fit.params[static_cast<std::size_t>(index)];
  if (!(p.std_error > 0) || !std::isfinite(p.std_error))
    throw InputError("profile likelihood: " + p.name + " has no standard error to start from");
  const int dof = fit.diagnostics.num_observations - fit.diagnostics.num_parameters;
  const double tq = t_multiplier(o.confidence, dof);
  PlSetup s;
  s.rss_min = fit.diagnostics.rss;
  // An exact fit has no residual variance to scale by; the floor keeps the threshold finite.
  s.s2 = std::max(s.rss_min / std::max(dof, 1), residual_variance_floor(problem.observed));
  const double f = std::max(1.0, o.variance_factor);
  s.threshold = f * tq * tq;
  s.half_width = std::sqrt(f) * tq * p.std_error;
  return s;
}

// One end: direction +1 (upper) or -1 (lower).
std::pair<double, bool> pl_end(PlProfile& prof, const ParamSpec& spec, double estimate, const PlSetup& s, int dir,
                               const ProfileOptions& o) {
  const double bound = dir > 0 ? spec.upper : spec.lower;
  auto g = [&](double v) { return (prof.rss(v) - s.rss_min) / s.s2 - s.threshold; };
  double inside = estimate, step = s.half_width;
  double outside = kNaN;
  for (int k = 0; k < o.max_steps; ++k) {
    double v = estimate + dir * step;
    bool at_bound = false;
    if (std::isfinite(bound) && dir * (v - bound) >= 0) v = bound, at_bound = true;
    if (g(v) > 0) {
      outside = v;
      break;
    }
    inside = v;
    if (at_bound) return {bound, true};
    step *= 2;
  }
  if (!std::isfinite(outside)) return {inside, true};  // never crossed within the steps: unbounded
  const double tol = o.tolerance * s.half_width;
  for (int k = 0; k < o.max_bisections && std::abs(outside - inside) > tol; ++k) {
    const double mid = 0.5 * (inside + outside);
    if (g(mid) > 0) outside = mid;
    else inside = mid;
  }
  // The end lies between; report the midpoint of the final bracket.
  return {0.5 * (inside + outside), false};
}

}  // namespace

double correlation(const FitResult& fit, std::size_t i, std::size_t j) {
  const std::size_t n = fit.params.size();
  if (fit.covariance.size() != n * n || i >= n || j >= n) return kNaN;
  const double d = std::sqrt(fit.covariance[i * n + i] * fit.covariance[j * n + j]);
  return d > 0 ? fit.covariance[i * n + j] / d : kNaN;
}

ProfileInterval profile_interval(const LsqProblem& problem, const FitResult& fit, int index, const ProfileOptions& o) {
  const auto s = pl_setup(problem, fit, index, o);
  PlProfile prof(problem, fit, index, o);
  const auto& spec = problem.params[static_cast<std::size_t>(index)];
  const double est = fit.params[static_cast<std::size_t>(index)].value;
  ProfileInterval r;
  std::tie(r.lo, r.lo_at_bound) = pl_end(prof, spec, est, s, -1, o);
  std::tie(r.hi, r.hi_at_bound) = pl_end(prof, spec, est, s, +1, o);
  r.solves = prof.solves();
  return r;
}

int apply_profile_intervals(const LsqProblem& problem, FitResult& fit, const ProfileOptions& o) {
  int solves = 0;
  const std::size_t n = fit.params.size();
  for (std::size_t j = 0; j < n; ++j) {
    auto& p = fit.params[j];
    if (p.fixed || !(p.std_error > 0) || !std::isfinite(p.std_error)) continue;
    const auto& spec = problem.params[j];
    double max_r = 0;
    for (std::size_t k = 0; k < n; ++k)
      if (k != j && !fit.params[k].fixed) max_r = std::max(max_r, std::abs(correlation(fit, j, k)));
    const auto s = pl_setup(problem, fit, static_cast<int>(j), o);
    bool unreliable =
        max_r > o.max_correlation || p.value - s.half_width <= spec.lower || p.value + s.half_width >= spec.upper;
    PlProfile prof(problem, fit, static_cast<int>(j), o);
    if (!unreliable) {
      // Curvature: at the Wald ends the profile must sit at the threshold (it does exactly for a
      // model linear in its parameters).
      for (double r : {prof.rss(p.value - s.half_width), prof.rss(p.value + s.half_width)}) {
        const double ratio = (r - s.rss_min) / s.s2 / s.threshold;
        if (!(ratio > 1 / o.curvature_tolerance && ratio < o.curvature_tolerance)) unreliable = true;
      }
    }
    if (!unreliable) {
      solves += prof.solves();
      continue;
    }
    // The Wald ends already solved are in the profile's cache: the stepping out starts there.
    const auto [lo, lo_b] = pl_end(prof, spec, p.value, s, -1, o);
    const auto [hi, hi_b] = pl_end(prof, spec, p.value, s, +1, o);
    solves += prof.solves();
    p.ci95_lo = std::min(lo, p.value);
    p.ci95_hi = std::max(hi, p.value);
    p.ci95_method = "profile-likelihood";
    if (lo_b || hi_b)
      fit.warnings.push_back("the 95 % profile-likelihood interval of " + p.name +
                             " is not closed by the data (it reaches " +
                             (lo_b && hi_b ? "both ends of the search"
                              : lo_b       ? "the lower end of the search"
                                           : "the upper end of the search") +
                             ")");
  }
  return solves;
}

}  // namespace tunekit::fitting
