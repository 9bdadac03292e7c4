#pragma once
// The tunekit command line as one function: what the `tunekit` executable runs, and what tests
// and benchmarks call in-process. How the commands are put together (CLI11) stays behind it.

#include <ostream>
#include <string>
#include <vector>

namespace tunekit::cli {

/// Runs the CLI on `args` (without the program name) and returns the exit code.
/// Never throws: errors are printed on `err` as one line.
int run_cli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace tunekit::cli
