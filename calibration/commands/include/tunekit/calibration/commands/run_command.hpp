#pragma once
// tunekit run as a function: run an experiment protocol (protocols/experiments.hpp) on a printer
// or on the built-in simulated printer, journaling every line and sensor sample into a run
// directory (protocols/runner.hpp), or with dry_run only build and check its G-code. The shape of
// a command is described in docs/cpp-api.md.

#include <chrono>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::calibration {

struct RunCommandOptions {
  /// Protocol, axis, machine ("sim" or a profile TOML), port, baud, run directory, link retries,
  /// limits (max_duration_s in s, max_lines) and dry_run: the runner's own options and defaults.
  /// compute_run() fills in params, link.timeout, the profile and (with "sim") the simulated
  /// printer; `progress` (human progress lines) is the caller's.
  protocols::RunOptions run;
  /// With --machine sim: the profile file of the printer to simulate (tunekit run --profile);
  /// empty: the built-in simulated printer.
  std::string profile_path;
  /// Simulator options KEY=VALUE (sim::SimConfig::from_options: "tau_s=0.5", "fault=drop@12").
  std::vector<std::string> sim_options;
  /// Protocol parameters as NAME=VALUE (value in the unit the name carries), checked by compute_run().
  std::vector<std::string> params;
  /// Asks the technician to do a set-up step before anything is sent (axis-sweep -p load_kg: the
  /// mass to place on the bed) and returns whether it was done; the caller's terminal. Empty (no
  /// terminal, CI): the step is taken as done as the options state it, and the run says so.
  std::function<bool(const std::string& instruction)> confirm_setup;
  /// Silence allowed while waiting for the firmware's "ok" (s); the link's default.
  double timeout_s = std::chrono::duration<double>(machine::LinkOptions{}.timeout).count();
};

struct RunOutcome {
  RunCommandOptions options;            ///< as given, with run.params parsed from `params`
  protocols::RunResult result;          ///< run directory, status, files by role, experiment, G-code (dry run)
  std::optional<nlohmann::json> truth;  ///< the simulator's truth.json, when the run wrote one
};

/// Checks the options (InputError, exit 2), then runs the protocol (MachineError, exit 3, when
/// the machine or link fails; the partial run directory is kept). SIGINT, SIGTERM or SIGHUP during
/// the run stops the machine and ends the run as "interrupted" (protocols/stop_signals.hpp).
RunOutcome compute_run(const RunCommandOptions& options);

Envelope to_envelope(const RunOutcome& outcome);
/// A dry run: the G-code, one line each. A run: its status, directory, files and the analysis
/// command for the data it recorded.
void print_text(const RunOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
