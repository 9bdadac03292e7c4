#pragma once
// tunekit export as a function: pressure/linear advance (K in s, smoothing time in s) and input
// shapers (frequency in Hz, damping ratio) designed from the results of `tunekit step`, `freq`,
// `shaper` and `rheo` (or values given directly), and the change of a Klipper printer.cfg, a
// Marlin Configuration_adv.h or a RepRapFirmware config.g that sets them.
//
// Unlike the analysis commands, export writes files (the configuration with its backup, G-code,
// an OrcaSlicer profile, post-processed G-code, and its own JSON results) and all of them are
// written together or none (core::FileBatch). So it is two steps: compute_export() designs
// everything and reads every input, writing nothing; commit_export() writes what the outcome
// holds, with the JSON results, and prints the summary. Shape of a command: command.hpp.

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration {

struct ExportOptions {
  std::string firmware;         ///< klipper, kalico, marlin or rrf
  bool marlin_ft_live = false;  ///< the running Marlin reported fixed-time motion active (M493)
  /// With marlin_ft_live: the form of its M493 report, as firmware::to_string(M493Syntax) names it
  /// ("mode", "axis_slash", "axis_named", "axis_list", "axis_list_v2"); empty: axis_named; "none"
  /// (a report that did not show its form): axis_named with a warning.
  std::string marlin_m493_form;
  std::string config;                ///< the configuration file to change
  std::vector<std::string> results;  ///< JSON results of step, freq, shaper, rheo
  std::string profile;               ///< machine profile TOML; empty: assumed defaults
  /// The profile at `profile` as its caller already loaded it, and the digest of the bytes it was
  /// read from (tunekit calibrate): export then reads nothing again.
  std::optional<machine::MachineProfile> loaded_profile;
  std::optional<InputDigest> loaded_profile_digest;
  double pa_k = fitting::kNaN;         ///< advance K (s) instead of the results; NaN: not given
  double pa_smooth = fitting::kNaN;    ///< smoothing time (s) instead of the design; NaN: not given
  double design_flow = fitting::kNaN;  ///< flow (mm^3/s) the single K is designed for; NaN: from the profile
  std::string shaper_x, shaper_y;      ///< TYPE:FREQ[:ZETA] instead of the results
  std::string shaper_z;                ///< TYPE:FREQ[:ZETA] of the Z shaper (Klipper only)
  std::string extruder = "extruder";   ///< Klipper section name, or a number N (extruder N everywhere)
  int drive = 0;                       ///< RepRapFirmware drive for M572 D
  bool drive_given = false;
  bool no_pa = false, no_shaper = false;
  bool write = false;                 ///< apply the change (backup + atomic replacement)
  std::string gcode_out;              ///< also write the settings as G-code here
  std::string sliced_in, sliced_out;  ///< per-feature advance: sliced G-code in, post-processed out
  double hysteresis = 0.10;           ///< relative change of K before the post-processor writes a new one
  std::string plot_out;               ///< the flow-dependent advance figure (SVG or PNG)
  std::string orca_in, orca_out, orca_name = "tunekit flow-dependent advance";
  /// The hot end's thermal model P:C:R:A:F[:H] (W, J/K, 1/s, W/K, W/K, J/(K mm)) instead of the
  /// results of `tunekit thermal`; written as Marlin's or Kalico's MPC, Klipper's PID, RRF's M307.
  std::string thermal_model;
  bool no_thermal = false;          ///< leave the temperature control alone
  int heater = 1;                   ///< RepRapFirmware heater number (M307 H)
  bool kalico_pid = false;          ///< Kalico: a PID designed from the model instead of its MPC
  double thermal_loop_delay = 0.8;  ///< s: the control loop's own delay in the PID design and RRF's D
};

struct ExportOutcome {
  ExportOptions options;
  firmware::ExportFirmware firmware{};
  firmware::CompensatorSettings settings;         ///< what is set
  std::optional<design::AdvanceDesign> design;    ///< the advance design, when one was made
  std::optional<design::FlowAdvanceDesign> flow;  ///< the flow-dependent design (two or more levels)
  /// 95 % interval of the advance K (s), when the design has one (export_design.hpp says how).
  std::optional<std::pair<double, double>> pa_k_ci95;
  firmware::ExportResult change;  ///< the configuration before/after, diff and G-code
  std::string schedule_gcode;     ///< flow-dependent advance as G-code (per feature)
  std::string backup;             ///< the backup's path when --write changes the file
  core::FileBatch files;          ///< everything commit_export() writes (not the JSON)
  Envelope envelope{"export"};
};

/// Designs and prepares every file; writes nothing. InputError (exit 2) for bad results files,
/// options or values outside the plausible or the firmware's limits. Reads options.results (the
/// JSON files a user names) with read_design_inputs() and designs from them.
ExportOutcome compute_export(const ExportOptions& options);
/// The same from typed design inputs (design_inputs.hpp; what calibrate hands over from its
/// analyses' outcomes); options.results is not read.
ExportOutcome compute_export(const ExportOptions& options, const DesignInputs& inputs);

inline const Envelope& to_envelope(const ExportOutcome& outcome) { return outcome.envelope; }
/// The configuration diff (stdout of the command).
void print_text(const ExportOutcome& outcome, std::ostream& os);

/// What became of the configuration, in one sentence: already up to date, written (and where its
/// backup is) or previewed only (add --write). The firmware's own next steps (RESTART, M502 + M500)
/// are outcome.change.notes.
std::string configuration_status(const ExportOutcome& outcome);

/// Writes the outcome's files and the JSON results (`output`) together or not at all, then
/// prints the diff and the summary as the command does. Returns the exit code. InputError when
/// the configuration changed since compute_export() read it.
int commit_export(const ExportOutcome& outcome, const OutputOptions& output, CliContext& ctx);

/// --shaper-x/--shaper-y TYPE:FREQ[:ZETA].
firmware::ShaperSetting parse_shaper_arg(const std::string& arg, const std::string& axis);

}  // namespace tunekit::calibration
