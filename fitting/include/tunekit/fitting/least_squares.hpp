#pragma once
// Bounded nonlinear least squares with parameter uncertainty, on Ceres Solver.
//
// A model describes its parameters (name, unit, start, bounds) and a residual function
// r(p) of length m. solve_least_squares() minimizes 1/2 sum r_i^2 with Levenberg-Marquardt,
// then computes the covariance of the estimate from the singular values of the Jacobian at the
// solution, with ceres::Covariance's dense-SVD rank test (so a rank-deficient Jacobian is
// detected and reported as "not identifiable" instead of giving meaningless intervals).
// Standard errors are scaled by the residual variance s^2 = rss / (m - k) unless the residuals
// are already divided by known standard deviations (`absolute_sigma`). 95 % intervals use the
// Student-t quantile with m - k degrees of freedom.
//
//   LsqProblem prob;
//   prob.params = {{"K", "1", 1.0}, {"tau_s", "s", 0.5, 1e-6, 100.0}};
//   prob.num_residuals = y.size();
//   prob.residuals = [&](const double* p, double* r) { ...; return true; };
//   prob.observed = y;               // for R^2
//   FitResult fit = solve_least_squares("first_order", prob);

#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::fitting {

struct ParamSpec {
  std::string name;
  std::string unit;
  double start = 0;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  bool fixed = false;
};

/// Fills `residuals` (length num_residuals) for parameters `p` (length params.size()).
/// Return false when `p` is outside the model's domain; the solver then backs off.
using ResidualFunction = std::function<bool(const double* p, double* residuals)>;
/// As ResidualFunction, and when `jacobian` is not null also fills the row-major
/// num_residuals x params.size() Jacobian d r_i / d p_j.
using ResidualJacobianFunction = std::function<bool(const double* p, double* residuals, double* jacobian)>;

struct LsqProblem {
  std::vector<ParamSpec> params;
  int num_residuals = 0;
  ResidualFunction residuals;                       ///< numeric (central) differences
  ResidualJacobianFunction residuals_and_jacobian;  ///< preferred when set
  /// residuals_and_jacobian computes the residuals the same way with and without the Jacobian,
  /// bit for bit: the solver then reuses residuals evaluated with a Jacobian at the same point.
  bool same_residuals_with_jacobian = false;
  std::vector<double> observed;            ///< optional: the data, to report R^2 = 1 - rss/tss
  bool residuals_are_time_ordered = true;  ///< run the whiteness test on residual order
};

struct LsqOptions {
  int max_iterations = 500;
  double function_tolerance = 1e-15;
  double gradient_tolerance = 1e-15;
  double parameter_tolerance = 1e-15;
  double confidence = 0.95;
  bool compute_covariance = true;
  bool absolute_sigma = false;  ///< residuals are already in units of their std. deviation
  /// Treat reaching max_iterations as failure (FitError). Keep true for user-facing fits.
  bool require_convergence = true;
  /// Reciprocal condition number of J^T J below which parameters are "not identifiable".
  double min_reciprocal_condition = 1e-14;
  /// Called once with the solution (before the residual statistics and the covariance): it may
  /// move free parameters onto a bound and mark them held (hold[j] = true), e.g. a parameter
  /// that ended on a bound where the residuals no longer depend on it. Held parameters are
  /// reported fixed and left out of the covariance, as if they had been fixed in the solve.
  std::function<void(std::vector<double>& x, std::vector<bool>& hold)> hold_before_covariance;
};

/// Solves the problem; throws FitError when the solver fails, the solution is not finite,
/// the iteration limit was reached (if require_convergence) or the covariance is singular
/// (if compute_covariance). The message names the parameters involved.
FitResult solve_least_squares(const std::string& model, const LsqProblem& problem, const LsqOptions& options = {});

/// Relative resolution of a residual: residual variances below (this * the largest |observed|,
/// or * 1 without observations)^2 count as zero. AIC and BIC use max(rss / n, floor), so an
/// exact fit has finite information criteria instead of ln(0).
inline constexpr double kRelativeResidualFloor = 1e-9;
/// The residual-variance floor for these observations (see kRelativeResidualFloor).
double residual_variance_floor(const std::vector<double>& observed);

/// Fills r.diagnostics statistics (rss, rms, r2, aic, bic, whiteness) from residuals.
/// Every statistic is finite for finite residuals: AIC/BIC floor the residual variance, and
/// R^2 of data that do not vary is 1 for a fit within the floor and 0 otherwise (with a warning).
void fill_residual_diagnostics(FitResult& r, const std::vector<double>& residuals, const std::vector<double>& observed,
                               bool time_ordered);
/// The same statistics, to the bit, without a buffer of the residuals' length: the whiteness
/// test runs in the residuals' own storage, so `residuals` is overwritten (for a caller that does
/// not need them afterwards).
void fill_residual_diagnostics_in_place(FitResult& r, std::span<double> residuals, std::span<const double> observed,
                                        bool time_ordered);

}  // namespace tunekit::fitting
