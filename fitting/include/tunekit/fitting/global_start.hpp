#pragma once
// Start values without a guess from the user: a derivative-free global search over the
// parameters' bounded box (NLopt's controlled random search with local mutation, CRS2-LM),
// then a local derivative-free polish (BOBYQA), then Ceres (solve_least_squares) for the
// final estimate and its covariance.
//
// Every free parameter needs finite bounds. A parameter whose box is positive and spans more
// than two decades is searched on a log scale. The search may use an evenly strided subset
// of the residuals (max_search_residuals) since it only has to find the right basin; the final
// Ceres refinement always uses every residual. The search is deterministic (fixed seed).

#include <string>
#include <vector>

#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

struct GlobalStartOptions {
  int max_evaluations = 2500;   ///< CRS2-LM budget (objective evaluations)
  int local_evaluations = 800;  ///< BOBYQA budget
  unsigned seed = 20190101;
  /// Multistart: also polish each parameter set listed here (e.g. a user's or a published
  /// start); the lowest cost wins.
  std::vector<std::vector<double>> extra_starts;
};

struct GlobalStartResult {
  std::vector<double> start;  ///< one value per LsqProblem parameter (fixed ones unchanged)
  double cost = 0;            ///< 1/2 sum r^2 of the searched problem
  int evaluations = 0;
};

/// Searches the box for a start; InputError when a free parameter lacks finite bounds.
GlobalStartResult global_start(const LsqProblem& problem, const GlobalStartOptions& options = {});

/// global_start (on `search`, when given, else on `problem`; same parameters), then
/// solve_least_squares on `problem` from the best start found. The FitResult's
/// diagnostics.solver names the global stage too.
FitResult solve_with_global_start(const std::string& model, LsqProblem problem, const GlobalStartOptions& global = {},
                                  const LsqOptions& options = {}, const LsqProblem* search = nullptr);

}  // namespace tunekit::fitting
