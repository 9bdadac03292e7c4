#include "tunekit/fitting/profile_likelihood.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <span>
#include <tuple>

#include <Eigen/Dense>

#include "tunekit/fitting/levenberg_marquardt.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::fitting {
namespace {

// The minimum of the residual sum of squares over the free parameters of a problem with an
// analytic Jacobian, from their starts: Levenberg-Marquardt on the normal equations J'J and J'r
// (levenberg_marquardt.hpp) to the convergence tests of Ceres Solver with the inner solve's
// tolerances. A profile point needs neither the covariance nor a QR factorisation of the
// m x k Jacobian (whose squared condition number the normal equations bear: the inner solves
// hold the profiled parameter, and their cost is stationary in the others, so S(v) keeps its
// digits). Returns S (HUGE_VAL where the model cannot be evaluated at the start) and sets x to
// where the parameters end.
class NormalEquationsSolve {
 public:
  explicit NormalEquationsSolve(const LsqProblem& prob)
      : prob_(prob), m_(static_cast<std::size_t>(prob.num_residuals)), n_(prob.params.size()) {}

  double operator()(std::vector<double>& x, const LsqOptions& o) {
    if (jac_.empty()) r_.resize(m_), jac_.resize(m_ * n_);  // once, for the profile's every point
    std::vector<double> lo(n_), hi(n_);
    std::vector<bool> fixed(n_);
    for (std::size_t q = 0; q < n_; ++q) {
      lo[q] = prob_.params[q].lower, hi[q] = prob_.params[q].upper, fixed[q] = prob_.params[q].fixed;
      x[q] = fixed[q] ? prob_.params[q].start : std::clamp(prob_.params[q].start, lo[q], hi[q]);
    }
    auto equations = [this](std::span<const double> q, Eigen::MatrixXd& N, Eigen::VectorXd& g) {
      return normal_equations(q, N, g);
    };
    lm_detail::Equations<Eigen::MatrixXd, Eigen::VectorXd> at;
    at.cost = equations(std::span<const double>(x), at.N, at.g);
    if (!std::isfinite(at.cost)) return HUGE_VAL;
    const lm_detail::Tolerances tol{o.function_tolerance, o.parameter_tolerance, o.gradient_tolerance,
                                    o.max_iterations};
    lm_detail::confirm(std::span<double>(x), std::span<const double>(lo), std::span<const double>(hi), fixed, equations,
                       at, lm_detail::kInitialDamping, tol);
    return at.cost;
  }

 private:
  // J'J and J'r at q; returns the residual sum of squares (HUGE_VAL outside the model's domain).
  double normal_equations(std::span<const double> q, Eigen::MatrixXd& N, Eigen::VectorXd& g) {
    N.setZero(static_cast<Eigen::Index>(n_), static_cast<Eigen::Index>(n_));
    g.setZero(static_cast<Eigen::Index>(n_));
    if (!prob_.residuals_and_jacobian(q.data(), r_.data(), jac_.data())) return HUGE_VAL;
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const Eigen::Map<const RowMajor> J(jac_.data(), static_cast<Eigen::Index>(m_), static_cast<Eigen::Index>(n_));
    const Eigen::Map<const Eigen::VectorXd> r(r_.data(), static_cast<Eigen::Index>(m_));
    N.noalias() = J.transpose() * J;
    g.noalias() = J.transpose() * r;
    const double rss = r.squaredNorm();
    return std::isfinite(rss) && N.allFinite() ? rss : HUGE_VAL;
  }

  const LsqProblem& prob_;
  std::size_t m_, n_;
  std::vector<double> r_, jac_;
};

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
    // The linearised profile trace: with p_j moved by dv, the other parameters' least-squares
    // values move by cov(q, j) / var(j) dv (the regression of p_q on p_j in the estimate's
    // covariance; Bates and Watts 1988, sec. 6.1.2). It predicts the first points of each side.
    const std::size_t n = best_.size();
    slope_.assign(n, 0.0);
    if (fit.covariance.size() == n * n && fit.covariance[j_ * n + j_] > 0)
      for (std::size_t q = 0; q < n; ++q)
        if (q != j_ && !prob_.params[q].fixed) slope_[q] = fit.covariance[q * n + j_] / fit.covariance[j_ * n + j_];
  }

  // S(v); +inf where the model cannot be fitted with p_j = v (outside its domain).
  double rss(double v) {
    if (auto it = solved_.find(v); it != solved_.end()) return it->second.first;
    ++solves_;
    // Warm start on the profile's trace predicted from the points already solved; when the
    // solve from there fails (the prediction left the model's domain), from the nearest point
    // as it is.
    auto [s, x] = solve_from(predicted_start(v), v);
    if (!std::isfinite(s)) std::tie(s, x) = solve_from(nearest(v)->second.second, v);
    solved_[v] = {s, x};
    return s;
  }
  int solves() const { return solves_; }

 private:
  using Solved = std::map<double, std::pair<double, std::vector<double>>>;

  Solved::const_iterator nearest(double v) const {
    auto it = solved_.lower_bound(v);
    if (it == solved_.end() || (it != solved_.begin() && std::abs(std::prev(it)->first - v) < std::abs(it->first - v)))
      --it;
    return it;
  }

  // The other parameters where the profile at v is expected: between two solved points, on the
  // line through them; beyond the last point of a side, on the line through its last two (or
  // along the linearised trace from the estimate); clamped into the bounds.
  std::vector<double> predicted_start(double v) const {
    auto finite = [](const Solved::value_type& e) { return std::isfinite(e.second.first); };
    const Solved::value_type *below = nullptr, *below2 = nullptr, *above = nullptr, *above2 = nullptr;
    for (const auto& e : solved_) {
      if (!finite(e)) continue;
      if (e.first < v) below2 = below, below = &e;
      else if (!above) above = &e;
      else if (!above2) above2 = &e;
    }
    const Solved::value_type *a = nullptr, *b = nullptr;  // extrapolate or interpolate from a towards b
    if (below && above) a = below, b = above;
    else if (below) a = below, b = below2;
    else if (above) a = above, b = above2;
    if (!a) return nearest(v)->second.second;
    std::vector<double> x = a->second.second;
    for (std::size_t q = 0; q < x.size(); ++q) {
      if (q == j_ || prob_.params[q].fixed) continue;
      const double d = b ? (b->second.second[q] - x[q]) / (b->first - a->first) : slope_[q];
      x[q] = std::clamp(x[q] + d * (v - a->first), prob_.params[q].lower, prob_.params[q].upper);
    }
    return x;
  }

  // S(v) with the other parameters started at `start`, and where they end (HUGE_VAL: failed).
  std::pair<double, std::vector<double>> solve_from(const std::vector<double>& start, double v) {
    for (std::size_t q = 0; q < prob_.params.size(); ++q) prob_.params[q].start = start[q];
    prob_.params[j_].start = v;
    double s = HUGE_VAL;
    std::vector<double> x = start;
    if (prob_.residuals_and_jacobian) {
      s = normal_solve_(x, inner_);
      x[j_] = v;
      return {s, x};
    }
    try {
      const auto r = solve_least_squares("profile", prob_, inner_);
      for (std::size_t q = 0; q < r.params.size(); ++q) x[q] = r.params[q].value;
      if (std::isfinite(r.diagnostics.rss)) s = r.diagnostics.rss;
    } catch (const Error&) {
      s = HUGE_VAL;
    }
    x[j_] = v;
    return {s, x};
  }

  LsqProblem prob_;
  std::size_t j_;
  NormalEquationsSolve normal_solve_{prob_};  // reads prob_'s starts at each solve
  LsqOptions inner_;
  std::vector<double> best_;
  std::vector<double> slope_;  // the linearised trace, per parameter
  Solved solved_;
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

// Fraction of the bisection's tolerance an interpolated point keeps from either end of the
// bracket: a point that close to the end lies on the other side of the crossing, and the bracket
// is then narrower than the tolerance. Just under one half, so that the two ends cannot meet.
constexpr double kBracketMargin = 0.45;

// The next point inside the bracket (inside, outside): where the profile t statistic
// sqrt((S(v) - S_min) / s^2) reaches sqrt(threshold) by linear interpolation between the ends
// (Bates and Watts 1988, sec. 6.1.2: tau(v) is exactly linear in v for a model linear in its
// parameters, and nearly so for a nearly linear one), kept kBracketMargin * tol from both ends;
// the midpoint where an end could not be fitted.
double bracket_point(PlProfile& prof, const PlSetup& s, double inside, double outside, double tol) {
  const double mid = 0.5 * (inside + outside);
  const double r_in = prof.rss(inside), r_out = prof.rss(outside);
  if (!std::isfinite(r_in) || !std::isfinite(r_out)) return mid;
  const double t_in = std::sqrt(std::max(0.0, r_in - s.rss_min) / s.s2), t_out = std::sqrt((r_out - s.rss_min) / s.s2);
  const double t_end = std::sqrt(s.threshold);
  if (!(t_out > t_end && t_in <= t_end)) return mid;
  const double v = inside + (outside - inside) * (t_end - t_in) / (t_out - t_in);
  const double lo = std::min(inside, outside) + kBracketMargin * tol,
               hi = std::max(inside, outside) - kBracketMargin * tol;
  return lo < hi ? std::clamp(v, lo, hi) : mid;
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
  int same_end = 0, last_end = 0;  // ends moved in a row on one side; which side moved last
  for (int k = 0; k < o.max_bisections && std::abs(outside - inside) > tol; ++k) {
    // Two interpolated points in a row on one side: the curvature of the profile keeps them
    // there (false position's slow end), so the next point halves the bracket.
    const double next = same_end >= 2 ? 0.5 * (inside + outside) : bracket_point(prof, s, inside, outside, tol);
    const int end = g(next) > 0 ? 1 : -1;
    (end > 0 ? outside : inside) = next;
    same_end = end == last_end ? same_end + 1 : 1;
    last_end = end;
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
