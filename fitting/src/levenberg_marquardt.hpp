#pragma once
// The Levenberg-Marquardt loop on small normal equations that polishes a start before the Ceres
// solve of the first-order step fits (single step and pooled). Each trial costs one pass over the
// samples and no Jacobian is stored. Damping scaled by the diagonal of J'J (Marquardt, An
// algorithm for least-squares estimation of nonlinear parameters, 1963); start value and the
// multiplicative update as in Press, Teukolsky, Vetterling and Flannery, Numerical Recipes,
// 3rd ed., 2007, ch. 15.5. Private to the fitting library.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
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
// Stop once an accepted step lowers the cost by less than this fraction: the Ceres solve that
// follows confirms the last digits.
inline constexpr double kStopRelativeDecrease = 1e-8;
// Iterations at most: the work on a long record stays bounded; a start not converged by then is
// handed to Ceres as it is.
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

/// Polishes p in place within [lo, hi], fixed[j] parameters held. normal_equations(q, N, g)
/// fills J'J and J'r at q and returns the residual sum of squares; each trial's normal equations
/// come with its cost, so an accepted step needs no second pass over the data.
template <class Matrix, class Vector, class Fixed, class NormalEquations>
void polish(std::span<double> p, std::span<const double> lo, std::span<const double> hi, const Fixed& fixed,
            NormalEquations&& normal_equations) {
  double lambda = kInitialDamping;
  Matrix N, N_q;
  Vector g, g_q;
  double cost = normal_equations(std::span<const double>(p), N, g);
  std::vector<double> q(p.size());
  for (int it = 0; it < kMaxIterations; ++it) {
    pin_fixed(N, g, fixed);
    bool improved = false;
    for (int trial = 0; trial < kMaxTrials && !improved; ++trial) {
      damped_trial(N, g, lambda, p, lo, hi, fixed, q);
      const double c = normal_equations(std::span<const double>(q), N_q, g_q);
      if (!(std::isfinite(c) && c < cost)) {
        lambda *= kDampingIncrease;
        continue;
      }
      const double rel = (cost - c) / std::max(cost, kTinyCost);
      std::copy(q.begin(), q.end(), p.begin());
      cost = c;
      N = N_q;
      g = g_q;
      lambda = std::max(lambda / kDampingDecrease, kMinDamping);
      improved = true;
      if (rel < kStopRelativeDecrease) return;
    }
    if (!improved) return;
  }
}

}  // namespace tunekit::fitting::lm_detail
