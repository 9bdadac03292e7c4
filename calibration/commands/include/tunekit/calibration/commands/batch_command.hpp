#pragma once
// tunekit batch as a function: every data file of a folder analysed on worker threads by the
// command its columns call for (step, freq, shaper, rheo), with one summary and one exit code.

#include <string>

#include "tunekit/calibration/results/context.hpp"

namespace tunekit::calibration {

struct BatchArgs {
  std::string dir;
  unsigned jobs = 0;
  OutputOptions output;
};

/// Analyses the folder and prints as the command does; returns the exit code (1 when an analysis
/// failed or a --require threshold is not met).
int run_batch(const BatchArgs& options, CliContext& ctx);

}  // namespace tunekit::calibration
