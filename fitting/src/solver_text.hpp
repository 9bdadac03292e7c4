#pragma once
// What a failed Ceres solve means, in plain words for a user's one-line error: Ceres' own
// messages ("Residual and Jacobian evaluation failed.", its Solver Report) stay in the fit's
// diagnostics and never reach the message.
#include <string>

#include <ceres/ceres.h>

namespace tunekit::fitting::detail {

inline std::string plain_solver_failure(const ceres::Solver::Summary& summary) {
  if (summary.message.find("evaluation failed") != std::string::npos)
    return "the model cannot be evaluated on these data (a value overflows or is not a number: check the data for "
           "huge or non-physical values)";
  return "the solver found no usable solution after " + std::to_string(summary.iterations.size()) +
         " iterations (the model may not describe these data)";
}

}  // namespace tunekit::fitting::detail
