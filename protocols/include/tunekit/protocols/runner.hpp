#pragma once
// Running an experiment protocol on a machine: the C++ API under `tunekit run` (and the base
// for `tunekit calibrate`). The protocol is built, checked against the machine profile (all
// violations listed; nothing is sent if there is one), then sent over the link while every
// line and sensor sample is journaled into the run directory.
//
//   RunOptions o;  o.protocol = "liquefier-step";  o.machine = "sim";
//   RunResult r = run_experiment(o);   // r.run_dir, r.files["load_cell"] = ".../step.csv"
//
// Machines: "sim" (the built-in simulated printer, served on a pseudo-terminal in a background
// thread of this process; its truth.json lands in the run directory) or a profile TOML path
// with `port`: a serial device, a pseudo-terminal (Klipper's /tmp/printer), or
// "unix:/tmp/klippy_uds" for Klipper's API server.
//
// Before the protocol is built for the machine, the firmware on the link is identified (M115, or
// Klipper's API server: info and the configuration in force): the protocol is built for that
// firmware, within the stricter of the profile's and the firmware's limits (a dry run uses the
// profile's firmware).
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
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/protocols/experiments.hpp"
#include "tunekit/machine/gcode_link.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::protocols {

/// The simulated camera's print bed (sim_camera.hpp; declared only, so that this header and the
/// code that runs experiments need no OpenCV).
}  // namespace tunekit::protocols
namespace tunekit::sim {
class SimPrintBed;
}  // namespace tunekit::sim
namespace tunekit::protocols {

struct RunOptions {
  std::string protocol;                  ///< see protocol_specs()
  std::map<std::string, double> params;  ///< protocol parameter overrides
  std::string axis = "x";                ///< axis protocols
  std::string machine = "sim";           ///< "sim" or a machine profile path (TOML or a firmware configuration)
  /// The machine's profile, already loaded (the C++ API's way; calibrate passes its own). With
  /// "sim" it is the printer the simulator simulates (SimConfig::for_machine): its limits,
  /// firmware, steps and extruder; otherwise the limits of the machine on `port`. Empty: the
  /// built-in simulated printer's profile, or the file `machine` names.
  std::optional<machine::MachineProfile> profile;
  /// "sim" only: the profile file of the printer to simulate (tunekit run --profile), when
  /// `profile` is empty.
  std::string profile_path;
  std::string port;  ///< device / PTY / "unix:PATH"; empty with "sim"
  int baud = 250000;
  std::string run_dir;   ///< default: <runs_root>/<protocol>-<UTC stamp>
  std::string file_tag;  ///< names raw_data_<axis>_<tag>.csv; default: the UTC stamp
  std::string runs_root = "runs";
  std::vector<std::string> sim_options;  ///< SimConfig::from_options keys ("tau_s=0.5", "fault=drop@12")
  /// "sim" only: what the simulated printer prints is laid down on this bed (for its camera,
  /// sim_camera.hpp); several runs may share one bed.
  std::shared_ptr<sim::SimPrintBed> sim_bed;
  machine::LinkOptions link;  ///< timeouts and retries
  ProtocolLimits limits;      ///< caps on the protocol's machine time, lines and bytes
  bool dry_run = false;       ///< build and check only; RunResult::gcode is filled
  /// A profile whose [machine] firmware differs from the firmware the machine identifies as is
  /// refused (InputError naming both) when set; otherwise the protocol is built for the firmware
  /// found and the difference is reported as a warning (run.json "warnings").
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
  std::map<std::string, std::string>
      files;  ///< role -> path: load_cell, accel, commanded_accel, journal, truth, gcode, summary
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
