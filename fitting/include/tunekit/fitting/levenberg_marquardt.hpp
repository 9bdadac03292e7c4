#pragma once
// The Levenberg-Marquardt loop on small normal equations J'J and J'r that the model computes
// itself: it polishes a start before the pooled first-order fit's Ceres solve, carries the
// single-step fit, the profile-likelihood points and the output-error fit of an axis
// (ident/axis_response_fit) to convergence by Ceres Solver's own tests (confirm). Each trial
// costs one evaluation of the normal equations; the m x k Jacobian need not be stored or
// factorised. Damping scaled by the diagonal of J'J (Marquardt, An algorithm for least-squares
// estimation of nonlinear parameters, 1963); start value and the multiplicative update as in
// Press, Teukolsky, Vetterling and Flannery, Numerical Recipes, 3rd ed., 2007, ch. 15.5.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace tunekit::fitting::lm_detail {

// First damping: Numerical Recipes' 1e-3, a nearly Gauss-Newton first step (the starts polished
// here are already near the optimum).
inline constexpr double kInitialDamping = 1e-3;
// Damping divided by this after an accepted step and multiplied by kDampingIncrease after a
// rejected one: gentler than Numerical Recipes' 10 each way, and unequal so that a rejection
// followed by an acceptance leaves the damping 4/3 larger instead of cycling between two values.
inline constexpr double kDampingDecrease = 3.0;
inline constexpr double kDampingIncrease = 4.0;
// Least damping: 1e-12 of the diagonal is about ten thousand rounding units of a double, a pure
// Gauss-Newton step in effect; less would only cost rejected trials to climb back.
inline constexpr double kMinDamping = 1e-12;
// Least diagonal element the damping is scaled by: a parameter the data do not move (a zero
// column of J) still gets a damped, finite step.
inline constexpr double kMinCurvature = 1e-12;
// The polish stops once an accepted step lowers the cost by less than this fraction: the Ceres
// solve that follows (pooled fit) or confirm() (single step) finishes the last digits.
inline constexpr double kStopRelativeDecrease = 1e-8;
// Polish iterations at most: the work on a long record stays bounded; a start not converged by
// then is handed on as it is.
inline constexpr int kMaxIterations = 60;
// Rejected trials in one iteration at most: 12 raise the damping 4^12 (about 1.7e7) times, to
// tiny gradient steps; when even those do not lower the cost the start is optimal to rounding.
inline constexpr int kMaxTrials = 12;
// Floor of the cost divided by in the relative decrease (an exact fit has cost 0).
inline constexpr double kTinyCost = 1e-300;

/// Fixed parameters get an identity row and column and no gradient: their step is 0.
template <class Matrix, class Vector, class Fixed>
void pin_fixed(Matrix& N, Vector& g, const Fixed& fixed) {
  for (Eigen::Index j = 0; j < N.rows(); ++j)
    if (fixed[static_cast<std::size_t>(j)]) {
      N.row(j).setZero();
      N.col(j).setZero();
      N(j, j) = 1;
      g(j) = 0;
    }
}

/// The damped step from p into q, clamped to [lo, hi]; fixed parameters stay.
template <class Matrix, class Vector, class Fixed>
void damped_trial(const Matrix& N, const Vector& g, double lambda, std::span<const double> p,
                  std::span<const double> lo, std::span<const double> hi, const Fixed& fixed, std::vector<double>& q) {
  Matrix A = N;
  for (Eigen::Index j = 0; j < A.rows(); ++j) A(j, j) += lambda * std::max(N(j, j), kMinCurvature);
  const Vector dp = A.ldlt().solve(-g);
  for (std::size_t j = 0; j < q.size(); ++j)
    q[j] = fixed[j] ? p[j] : std::clamp(p[j] + dp(static_cast<Eigen::Index>(j)), lo[j], hi[j]);
}

/// Which parameters a step holds: the fixed ones and, with `active_bounds`, those at a bound the
/// gradient g = J'r pushes them against (an active bound). The damped step of the others then
/// does not count on a move that the bound would cut off; without this, a step clamped at the
/// bound leaves the others off their best values and the iteration creeps along the bound.
template <class Vector, class Fixed>
std::vector<char> held(std::span<const double> p, std::span<const double> lo, std::span<const double> hi,
                       const Vector& g, const Fixed& fixed, bool active_bounds) {
  std::vector<char> h(p.size());
  for (std::size_t j = 0; j < p.size(); ++j) {
    const double gj = g(static_cast<Eigen::Index>(j));
    h[j] = fixed[j] || (active_bounds && ((p[j] <= lo[j] && gj > 0) || (p[j] >= hi[j] && gj < 0)));
  }
  return h;
}

/// The normal equations J'J and J'r at a point with its cost (the residual sum of squares).
template <class Matrix, class Vector>
struct Equations {
  Matrix N;
  Vector g;
  double cost = 0;
};

/// Polishes p in place within [lo, hi], fixed[j] parameters held, from the equations `at` at p
/// and the damping `lambda`; both are updated to the end point. normal_equations(q, N, g) fills
/// J'J and J'r at q and returns the residual sum of squares; each trial's normal equations come
/// with its cost, so an accepted step needs no second pass over the data. `active_bounds`: hold
/// parameters at active bounds in each step (see held()).
template <class Matrix, class Vector, class Fixed, class NormalEquations>
void polish_from(std::span<double> p, std::span<const double> lo, std::span<const double> hi, const Fixed& fixed,
                 NormalEquations&& normal_equations, Equations<Matrix, Vector>& at, double& lambda,
                 bool active_bounds = false) {
  Matrix N_q;
  Vector g_q;
  std::vector<double> q(p.size());
  for (int it = 0; it < kMaxIterations; ++it) {
    Matrix N = at.N;
    Vector g = at.g;
    const auto hold = held(std::span<const double>(p), lo, hi, g, fixed, active_bounds);
    pin_fixed(N, g, hold);
    bool improved = false;
    for (int trial = 0; trial < kMaxTrials && !improved; ++trial) {
      damped_trial(N, g, lambda, p, lo, hi, hold, q);
      const double c = normal_equations(std::span<const double>(q), N_q, g_q);
      if (!(std::isfinite(c) && c < at.cost)) {
        lambda *= kDampingIncrease;
        continue;
      }
      const double rel = (at.cost - c) / std::max(at.cost, kTinyCost);
      std::copy(q.begin(), q.end(), p.begin());
      at = {N_q, g_q, c};
      lambda = std::max(lambda / kDampingDecrease, kMinDamping);
      improved = true;
      if (rel < kStopRelativeDecrease) return;
    }
    if (!improved) return;
  }
}

/// polish_from a start p, with the first damping kInitialDamping.
template <class Matrix, class Vector, class Fixed, class NormalEquations>
void polish(std::span<double> p, std::span<const double> lo, std::span<const double> hi, const Fixed& fixed,
            NormalEquations&& normal_equations) {
  Equations<Matrix, Vector> at;
  at.cost = normal_equations(std::span<const double>(p), at.N, at.g);
  double lambda = kInitialDamping;
  polish_from(p, lo, hi, fixed, normal_equations, at, lambda);
}

/// The residuals of the two evaluations with the lowest cost so far, each with its parameters:
/// the end point of polish_from and confirm is one of them (confirm may end on a trial that
/// lowered the cost but was not taken), so a model that stores its residuals while it evaluates
/// its normal equations needs no further pass for the residuals at the end point.
class ResidualMemo {
 public:
  explicit ResidualMemo(std::size_t n) : trial_(n), best_(n) {}
  /// Where the next evaluation stores its residuals.
  std::span<double> trial() { return trial_; }
  /// After an evaluation at q into trial() with the residual sum of squares c.
  void evaluated(std::span<const double> q, double c) {
    if (!(c < best_cost_)) {
      trial_p_.assign(q.begin(), q.end());
      return;
    }
    std::swap(trial_, best_);
    trial_p_ = std::move(best_p_);
    best_p_.assign(q.begin(), q.end());
    best_cost_ = c;
  }
  /// The residuals at p (moved out), or an empty vector when neither kept evaluation is at p.
  std::vector<double> take(std::span<const double> p) {
    auto at_p = [&p](const std::vector<double>& q) { return std::equal(q.begin(), q.end(), p.begin(), p.end()); };
    if (at_p(best_p_)) return std::move(best_);
    if (at_p(trial_p_)) return std::move(trial_);
    return {};
  }

 private:
  std::vector<double> trial_, best_, trial_p_, best_p_;
  double best_cost_ = HUGE_VAL;
};

/// Convergence tests of confirm(): those of Ceres Solver's trust-region minimizer (Agarwal,
/// Mierle and others, Ceres Solver 2.1, 2022: Solver::Options), with the same meaning.
struct Tolerances {
  double function = 1e-12;   ///< |cost change of a trial| <= function * cost
  double parameter = 1e-12;  ///< |trial step| <= parameter * (|p| + parameter), Euclidean norms
  double gradient = 1e-15;   ///< max_j |p_j - clamp(p_j - g_j, lo_j, hi_j)| <= gradient, g = J'r
  int max_iterations = 500;
};

/// How confirm() ended: converged by one of the tolerances, or not (then another solver should
/// take over from p).
enum class ConfirmEnd { function_tolerance, parameter_tolerance, gradient_tolerance, no_decrease, iteration_limit };

struct Confirmed {
  ConfirmEnd end = ConfirmEnd::iteration_limit;
  int iterations = 0;       ///< iterations run (each solves the damped normal equations once or more)
  int rejected_trials = 0;  ///< trials that raised the cost: the cost is not smooth or not quadratic there
  bool converged() const {
    return end == ConfirmEnd::function_tolerance || end == ConfirmEnd::parameter_tolerance ||
           end == ConfirmEnd::gradient_tolerance;
  }
};

/// Continues the Levenberg-Marquardt iteration of polish_from until one of Ceres Solver's
/// convergence tests holds: the gradient is small, or a trial moves the parameters or changes
/// the cost by less than the tolerances. As in Ceres, such a trial is not taken: p stays the
/// last accepted point and `at` holds its equations. Parameters at active bounds are held in
/// each step (held()). With `cost` (cost(q) returns the residual sum of squares alone), each
/// trial is first costed by it, and only a trial that is taken has its normal equations
/// evaluated: for a model whose equations cost several times its residuals, since the last
/// trial (the one that meets a tolerance) and rejected ones need no equations.
template <class Matrix, class Vector, class Fixed, class NormalEquations, class Cost = std::nullptr_t>
Confirmed confirm(std::span<double> p, std::span<const double> lo, std::span<const double> hi, const Fixed& fixed,
                  NormalEquations&& normal_equations, Equations<Matrix, Vector>& at, double lambda,
                  const Tolerances& tol, Cost&& cost = nullptr) {
  constexpr bool kCostFirst = !std::is_null_pointer_v<std::remove_cvref_t<Cost>>;
  Matrix N_q;
  Vector g_q;
  std::vector<double> q(p.size());
  Confirmed out;
  auto end = [&out](ConfirmEnd e) {
    out.end = e;
    return out;
  };
  while (out.iterations < tol.max_iterations) {
    ++out.iterations;
    Matrix N = at.N;
    Vector g = at.g;
    double projected_gradient = 0, p_norm = 0;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const double gj = g(static_cast<Eigen::Index>(j));
      if (!fixed[j])
        projected_gradient = std::max(projected_gradient, std::abs(p[j] - std::clamp(p[j] - gj, lo[j], hi[j])));
      p_norm += p[j] * p[j];
    }
    const auto hold = held(std::span<const double>(p), lo, hi, g, fixed, true);
    pin_fixed(N, g, hold);
    if (projected_gradient <= tol.gradient) return end(ConfirmEnd::gradient_tolerance);
    p_norm = std::sqrt(p_norm);
    bool improved = false;
    for (int trial = 0; trial < kMaxTrials && !improved; ++trial) {
      damped_trial(N, g, lambda, p, lo, hi, hold, q);
      double step = 0;
      for (std::size_t j = 0; j < p.size(); ++j) step += (q[j] - p[j]) * (q[j] - p[j]);
      if (std::sqrt(step) <= tol.parameter * (p_norm + tol.parameter)) return end(ConfirmEnd::parameter_tolerance);
      double c;
      if constexpr (kCostFirst) c = cost(std::span<const double>(q));
      else c = normal_equations(std::span<const double>(q), N_q, g_q);
      if (std::isfinite(c) && std::abs(at.cost - c) <= tol.function * at.cost)
        return end(ConfirmEnd::function_tolerance);
      if (!(std::isfinite(c) && c < at.cost)) {
        lambda *= kDampingIncrease;
        ++out.rejected_trials;
        continue;
      }
      if constexpr (kCostFirst) c = normal_equations(std::span<const double>(q), N_q, g_q);
      std::copy(q.begin(), q.end(), p.begin());
      at = {N_q, g_q, c};
      lambda = std::max(lambda / kDampingDecrease, kMinDamping);
      improved = true;
    }
    if (!improved) return end(ConfirmEnd::no_decrease);
  }
  return end(ConfirmEnd::iteration_limit);
}

}  // namespace tunekit::fitting::lm_detail
