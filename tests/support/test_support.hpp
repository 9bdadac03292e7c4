#pragma once
// Helpers shared by the tests: running the CLI in-process, scratch files, dataset paths.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::test {

struct CliRun {
  int code = -1;
  std::string out;
  std::string err;
};

/// Runs `tunekit ARGS...` in-process (same code path as the executable).
CliRun run_cli(const std::vector<std::string>& args);

/// Runs a command of calibrate's results.reproduce list ("tunekit WORD...", paths relative to the
/// run directory) in-process from anywhere: each word naming a file of `run_dir` is made
/// absolute; `extra` words (e.g. "--json") are appended. Throws unless it starts with "tunekit".
CliRun run_reproduce_command(const std::string& run_dir, const std::string& command,
                             const std::vector<std::string>& extra = {});

/// The default simulated calibration (`tunekit calibrate --machine sim --out DIR`, nothing else),
/// run once per build of the tests and shared by the tests that only read what it wrote and
/// printed: ctest runs each test case as its own process, and a whole calibration is the
/// longest thing most of them do (about 4 s, 15 s under the sanitizers). The first process to
/// ask runs it under a file lock; the others wait for it and read the same run. A new tunekit
/// executable (a rebuild) runs it again. A test that writes into the run directory, or needs
/// other options, runs its own calibration.
struct SharedCalibration {
  std::string dir;  // the run directory (read only)
  CliRun cli;       // its exit code, stdout and stderr
};
const SharedCalibration& default_calibration();

/// Runs the built tunekit executable through the shell (for end-to-end checks of the real
/// process: exit status, stdout/stderr separation). `args` is appended as one shell string.
CliRun run_exe(const std::string& args);
/// run_exe() with `prefix` (a command such as "setpriv ... " or "prlimit ... ") before the executable.
CliRun run_exe_prefixed(const std::string& prefix, const std::string& args);

/// The whole content of the file at `path` ("" if it cannot be read).
std::string read_text(const std::string& path);

/// The JSON document in the file at `path` (throws nlohmann::json::parse_error if it is not JSON).
nlohmann::json read_json(const std::string& path);

/// Path of a file under the repository's datasets/ folder.
std::string dataset(const std::string& relative);

/// A fresh, empty scratch directory for the calling test, named after `name`.
std::string scratch_dir(const std::string& name);

/// Writes `content` to scratch file `name` (in scratch_dir("files")) and returns its path.
std::string write_scratch(const std::string& name, const std::string& content);

/// Length of the base64 image data of the report figure `<figure id="plot-ID">` (0 if absent
/// or not an SVG or PNG data URI). Scans the text directly: the data run is far too long for
/// std::regex.
std::size_t embedded_image_base64_length(const std::string& html, const std::string& id);
/// The same, for a figure that must be a PNG (the line-width photo): 0 for an SVG.
std::size_t embedded_png_base64_length(const std::string& html, const std::string& id);

struct SummaryCell {
  std::string path, value, display;
};
/// The numeric cells of the report's summary table (data-path, data-value, shown text).
std::vector<SummaryCell> summary_cells(const std::string& html);

/// Splits a shell command line into words (single and double quotes, no expansion).
std::vector<std::string> shell_words(const std::string& line);

/// The diagonal of (J'J)^-1 for a Jacobian given as its columns (one per parameter), by
/// Gauss-Jordan elimination with partial pivoting: times s^2 = rss / (m - k), the variances of a
/// least-squares fit's parameters, to check a fit's analytic Jacobian against differences.
std::vector<double> inverse_normal_diagonal(const std::vector<std::vector<double>>& columns);

}  // namespace tunekit::test
