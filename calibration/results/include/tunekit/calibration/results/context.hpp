#pragma once
// What every subcommand gets: where to print, how verbose to be, and the shared output
// options (--json, --output). Commands write results to `out` and diagnostics to `err`,
// never to std::cout directly, so the whole CLI can run in-process in tests.

#include <iosfwd>
#include <string>
#include <vector>

namespace tunekit::calibration {

struct CliContext {
  std::ostream& out;
  std::ostream& err;
  int verbosity = 0;         ///< -v count; 0 is quiet
  bool interactive = false;  ///< stderr is a terminal (progress bars allowed)
  std::string program = "tunekit";
};

/// Options shared by every analysis command.
struct OutputOptions {
  bool json = false;                 ///< print the JSON envelope on stdout
  std::string output_path;           ///< also write the JSON envelope to this file
  std::vector<std::string> require;  ///< CI thresholds, e.g. "tau_s<0.6"
  // The calibration history (tunekit/calibration/results/history_record.hpp): --record --machine-id NAME --db DB.
  bool record = false;        ///< also store the result in the history database
  std::string machine_id;     ///< whose result it is (calibrate falls back to the profile's [machine] id)
  std::string db;             ///< SQLite file or postgresql:// URL (default: history.sqlite)
  std::string record_source;  ///< set by the command: the run directory the result belongs to
};

/// True when the JSON envelope leaves the process (--json, a results file, --record): only then
/// are the inputs' digests shown or stored.
inline bool envelope_leaves_process(const OutputOptions& o) { return o.json || !o.output_path.empty() || o.record; }

}  // namespace tunekit::calibration
