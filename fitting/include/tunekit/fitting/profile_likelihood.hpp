#pragma once
// Profile-likelihood confidence intervals for least-squares fits, for the parameters whose
// linearised (Wald) interval cannot be trusted: strongly correlated parameters on a curved
// ridge, a curved likelihood, or a bound nearby (Venzon and Moolgavkar, A method for computing
// profile-likelihood-based confidence intervals, Applied Statistics 37, 1988; Bates and Watts,
// Nonlinear Regression Analysis and Its Applications, Wiley, 1988, sec. 6.1).
//
// For parameter j the profile is S(v) = min over the other free parameters of the residual sum
// of squares with p_j held at v. The interval is every v with
//     (S(v) - S_min) / s^2 <= t^2(m - k),    s^2 = S_min / (m - k),
// t the Student-t quantile of the confidence level with m - k degrees of freedom: for a model
// linear in its parameters this is exactly the Student-t (Wald) interval, on a curved ridge it
// follows the ridge, which the linearised interval cannot.
//
// Each end is found by stepping out from the estimate (first step: the Wald half-width; then
// doubling) until the profile crosses the threshold, then narrowing the bracket to the tolerance:
// each new point where the profile t statistic sqrt((S(v) - S_min) / s^2), interpolated linearly
// between the bracket's ends, reaches the threshold's root (exact for a model linear in its
// parameters), kept a little inside the bracket, and a bisection when two points in a row fall on
// one side. Every profile point is a solve of the other parameters (Levenberg-Marquardt on the
// normal equations when the problem has an analytic Jacobian, otherwise solve_least_squares
// without covariance) started where the points already solved predict the profile's trace (the
// line through the two neighbouring points, or the covariance's regression from the estimate),
// so an end costs a handful of short solves. An end that reaches the parameter's bound without
// crossing is reported at the bound (`*_at_bound`): the data do not bound the parameter there.
//
// Everything here is in the coordinates the problem is solved in (a parameter estimated as a
// logarithm has its interval in ln; transform both ends).
//
//   auto fit = solve_least_squares("model", prob);
//   auto pl = profile_intervals(prob, fit);        // decides per parameter, replaces intervals
//   // fit.params[j].ci95_method is "wald" or "profile-likelihood"

#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

struct ProfileOptions {
  double confidence = 0.95;
  /// A Wald interval is kept when no correlation with another free parameter exceeds this (|r|)...
  double max_correlation = 0.95;
  /// ...and the profile at both Wald ends lies within this factor of the threshold (curvature).
  double curvature_tolerance = 1.3;
  /// Bisection stops when the bracket is narrower than this fraction of the Wald half-width.
  double tolerance = 0.01;
  int max_steps = 24;       ///< stepping-out steps per side
  int max_bisections = 30;  ///< per side
  int inner_max_iterations = 200;
  /// Variance inflation for residuals that are not white (1: none): the threshold becomes
  /// f t^2 and the first step sqrt(f) times the Wald half-width, as for a record of n / f
  /// independent residuals.
  double variance_factor = 1.0;
};

/// One parameter's profile interval, in solver coordinates.
struct ProfileInterval {
  double lo = kNaN, hi = kNaN;
  bool lo_at_bound = false, hi_at_bound = false;
  int solves = 0;  ///< profile points evaluated
};

/// The profile interval of parameter `index` of `problem` around the solution `fit`
/// (solve_least_squares' result on the same problem, with covariance). Throws InputError for
/// a fixed parameter or a fit without a standard error.
ProfileInterval profile_interval(const LsqProblem& problem, const FitResult& fit, int index,
                                 const ProfileOptions& options = {});

/// For every free parameter of `fit`, decides whether its Wald interval holds (correlation,
/// curvature at the Wald ends and bounds as in ProfileOptions) and replaces the interval by the
/// profile interval when it does not; sets Param::ci95_method ("wald" or "profile-likelihood")
/// and adds a warning for each end at a bound. Returns the number of profile solves.
int apply_profile_intervals(const LsqProblem& problem, FitResult& fit, const ProfileOptions& options = {});

/// Correlation coefficient of free parameters i and j from fit.covariance (NaN if absent).
double correlation(const FitResult& fit, std::size_t i, std::size_t j);

}  // namespace tunekit::fitting
