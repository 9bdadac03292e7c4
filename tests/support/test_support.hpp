#pragma once
// Helpers shared by the tests: running the CLI in-process, scratch files, dataset paths.

#include <string>
#include <vector>

namespace tunekit::test {

struct CliRun {
  int code = -1;
  std::string out;
  std::string err;
};

/// Runs `tunekit ARGS...` in-process (same code path as the executable).
CliRun run_cli(const std::vector<std::string>& args);

/// Runs the built tunekit executable through the shell (for end-to-end checks of the real
/// process: exit status, stdout/stderr separation). `args` is appended as one shell string.
CliRun run_exe(const std::string& args);

/// Path of a file under the repository's datasets/ folder.
std::string dataset(const std::string& relative);

/// A fresh, empty scratch directory for the calling test, named after `name`.
std::string scratch_dir(const std::string& name);

/// Writes `content` to scratch file `name` (in scratch_dir("files")) and returns its path.
std::string write_scratch(const std::string& name, const std::string& content);

}  // namespace tunekit::test
