#pragma once
// Ceres reports through glog; the library reads the solver's outcome from its summary and
// reports errors as FitError, so glog is kept off stderr (internal to the fitting library).

namespace tunekit::fitting {

/// Nothing below FATAL from glog, and nothing to stderr, for the rest of the program. Called by
/// every function that runs a Ceres solve.
void quiet_solver_logging();

}  // namespace tunekit::fitting
