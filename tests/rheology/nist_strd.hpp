#pragma once
// NIST StRD nonlinear regression reference problems (public domain, itl.nist.gov/div898/strd):
// a reader for their .dat files, the model of each problem, and a fit of a problem from one
// of its two certified starting points with the project's least-squares core. Used to check
// that solve_least_squares reaches certified values and certified standard deviations.

#include <optional>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/global_start.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

struct NistProblem {
  std::string name;  ///< "MGH09", from the file's "Dataset Name"
  std::vector<double> x, y;
  std::vector<double> start1, start2, certified, certified_sd;
  double certified_rss = 0;
  double certified_residual_sd = 0;
  std::string difficulty;  ///< "Lower", "Average" or "Higher"
};

/// Reads a StRD .dat file; InputError (FILE:LINE) when it is not one or the model is unknown.
NistProblem read_nist_problem(const std::string& path);

/// The least-squares problem (analytic Jacobian by automatic differentiation) from `start`.
LsqProblem nist_lsq_problem(const NistProblem& p, const std::vector<double>& start);

/// The options used for the StRD checks: tight tolerances, a large iteration budget.
LsqOptions nist_lsq_options();

/// Log relative error: number of correct significant digits of `estimate` (capped at 11).
double log_relative_error(double estimate, double certified);

struct NistOutcome {
  std::string problem;
  int start = 1;               ///< 1 or 2
  bool global_search = false;  ///< the start came from the global search
  bool solved = false;         ///< the fit returned (converged, covariance computed)
  std::string error;           ///< the FitError message when not solved
  std::vector<double> estimate, std_error;
  double min_lre_params = 0;  ///< fewest correct digits over the parameters
  double min_lre_sd = 0;      ///< fewest correct digits over the standard deviations
  double lre_rss = 0;
  int iterations = 0;
};

/// Fits the problem from start 1 or 2 with solve_least_squares and scores it against the
/// certified values. With `global`, the start is first improved by the global search over the
/// box [start/1000, start*1000] (sign-aware, around the certified start) before Ceres refines it.
NistOutcome solve_nist_problem(const NistProblem& p, int start, bool global = false);

}  // namespace tunekit::fitting
