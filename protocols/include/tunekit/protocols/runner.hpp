#pragma once
// Running an experiment protocol on a machine: the C++ API under `tunekit run` (and the base
// for `tunekit calibrate`). The protocol is built, checked against the machine profile (all
// violations listed; nothing is sent if there is one), then sent over the link while every
// line and sensor sample is journaled into the run directory.
//
//   RunOptions o;  o.protocol = "liquefier-step";  o.profile = ...;  o.port = "/dev/ttyACM0";
//   RunResult r = run_experiment(o);   // r.run_dir, r.files[RunFile::load_cell] = ".../step.csv"
//
// The machine is the printer on `port` (a serial device, a pseudo-terminal such as Klipper's
// /tmp/printer, or "unix:/tmp/klippy_uds" for Klipper's API server), checked against the
// machine profile the caller loaded, or a machine the runner brings up itself for each run
// (RunOptions::host, machine_host.hpp): calibration/ serves the simulated printer that way, on a
// pseudo-terminal in a background thread of this process, its truth.json in the run directory.
//
// Before the protocol is built for the machine, the firmware on the link is identified (M115, or
// Klipper's API server: info and the configuration in force): the protocol is built for that
// firmware, within the stricter of the profile's and the firmware's limits (a dry run uses the
// profile's firmware, or the one the host says its machine runs).
//
// Failures: a limit violation or bad parameter is an InputError (exit 2) before anything is
// opened; a machine/transport failure is a MachineError (exit 3) thrown after the journal has
// been flushed, safe-state commands sent (best effort) and run.json written with
// "status": "failed" — everything received before the failure stays in the run directory.
// SIGINT, SIGTERM and SIGHUP at any instant of a run, up to and after the last line's answer, do
// the same with "status": "interrupted" and "stopped_at" saying where, and throw InterruptedError
// (exit code 130, 143, 129) (stop_signals.hpp); with the caller's own abort_flag, a MachineError.
// A run whose protocol heated turns the heaters off at its normal end (RunOptions::keep_heaters).

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/machine_host.hpp"
#include "tunekit/protocols/run_files.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

struct RunOptions {
  std::string protocol;                  ///< see protocol_specs()
  std::map<std::string, double> params;  ///< protocol parameter overrides
  std::string axis = "x";                ///< axis protocols
  /// The machine as run.json names it: "sim", or the path of its profile (TOML or a firmware
  /// configuration).
  std::string machine = "sim";
  /// The machine's profile, loaded by the caller once for all its runs: the limits every line is
  /// checked against. With a `host` serving the simulated printer it is the printer simulated.
  machine::MachineProfile profile;
  /// The machine the runner brings up for each run (the simulated printer); null: the printer on
  /// `port`.
  std::shared_ptr<const MachineHost> host;
  std::string port;  ///< device / PTY / "unix:PATH"; with a `host`, empty (or an outside link to it)
  int baud = 250000;
  std::string run_dir;   ///< default: <runs_root>/<protocol>-<UTC stamp>
  std::string file_tag;  ///< names raw_data_<axis>_<tag>.csv; default: the UTC stamp
  std::string runs_root = "runs";
  machine::LinkOptions link;  ///< timeouts and retries
  ProtocolLimits limits;      ///< caps on the protocol's machine time, lines and bytes
  bool dry_run = false;       ///< build and check only; RunResult::gcode is filled
  /// A profile whose [machine] firmware differs from the firmware the machine identifies as is
  /// refused (InputError naming both) when set; otherwise the protocol is built for the firmware
  /// found and the difference is reported as a warning (run.json "warnings"). A machine the
  /// runner brings up (`host`) runs the firmware it was set up with, whatever the profile names.
  bool strict_firmware = false;
  /// A protocol that heats the hot end or the bed turns them off at its normal end (after its
  /// epilogue) unless this is set (`--keep-heaters`): then they stay at the protocol's last
  /// temperatures, for a run that follows at once.
  bool keep_heaters = false;
  /// Set to stop the run safely; default: set by SIGINT, SIGTERM or SIGHUP (stop_signals.hpp).
  const std::atomic<bool>* abort_flag = nullptr;
  std::function<void(const std::string&)> progress;  ///< human progress messages
};

struct RunResult {
  std::string run_dir;  ///< empty for a dry run
  std::string status;   ///< "complete" or "dry-run"
  RunFiles files;       ///< what each file of the run holds -> its path (run_files.hpp)
  Experiment experiment;
  std::vector<std::string> gcode;  ///< the protocol's G-code (with ;@record directives)
  nlohmann::json summary;          ///< what run.json holds
  /// Marlin's fixed-time motion as its M493 report said: "active", "built, inactive", or empty
  /// (not built in, or not Marlin). Also in summary.firmware.ft_motion.
  std::string ft_motion;
  /// The form of that M493 report, whose letters set its shapers (firmware::to_string(M493Syntax):
  /// "mode" .. "axis_list_v2"); also summary.firmware.m493_form. Empty without FT_MOTION.
  std::string m493_form;
};

/// Runs (or, with dry_run, only builds and checks) an experiment. See the header comment.
RunResult run_experiment(const RunOptions& options);

/// For a caller that keeps a StopSignals guard after a run completed (the analysis of `run`,
/// calibrate's stages): when a stop signal has arrived, rewrites the run's run.json as
/// "interrupted" with "stopped_at": `where` and throws InterruptedError (exit code 128 + the
/// signal's number); nothing otherwise.
void throw_if_stopped_after_run(const RunResult& run, const std::string& where);

}  // namespace tunekit::protocols
