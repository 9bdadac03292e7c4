#pragma once
// Firmware configuration export: pressure/linear advance and input shaping written into a
// Klipper printer.cfg, a Marlin Configuration_adv.h or a RepRapFirmware config.g, with
// everything else preserved byte for byte, a unified-diff preview, and (on request) a
// timestamped backup plus atomic replacement. Used by `tunekit export` and `tunekit calibrate`.
//
// Targeted versions and accepted ranges are documented in docs/export.md:
//   Klipper (mainline, 2024-2025): pressure_advance >= 0, 0 < pressure_advance_smooth_time <= 0.2 s,
//     shaper types zv mzv zvd ei 2hump_ei 3hump_ei, shaper_freq > 0, 0 <= damping_ratio < 1.
//   Marlin 2.1.2 and bugfix-2.1.x: K 0..10 (M900 K, ADVANCE_K), ADVANCE_TAU / M900 U 0..0.5 s
//     (SMOOTH_LIN_ADVANCE, bugfix-2.1.x), input shaping ZV only on X and Y, 0 <= zeta < 1.
//   RepRapFirmware 3.5-3.6: M572 D0 S>=0, M593 P"mzv|zvd|zvdd|zvddd|ei2|ei3" F7.16..1000 S0..0.99,
//     one shaper for all axes.

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/firmware/marlin_m493.hpp"
#include "tunekit/firmware/thermal_export.hpp"
#include "tunekit/design/pressure_advance.hpp"

namespace tunekit::firmware {

/// kalico: the Klipper fork (KalicoCrew/kalico) with nonlinear pressure advance; its printer.cfg
/// is Klipper's dialect, edited by the same writer.
enum class ExportFirmware { klipper, marlin, rrf, kalico };

/// "klipper", "kalico", "marlin", "rrf" (also "reprapfirmware", "duet"); InputError otherwise.
ExportFirmware parse_export_firmware(const std::string& name);
std::string to_string(ExportFirmware fw);

/// One axis's input shaper. `type` uses Klipper's spelling (zv, mzv, zvd, zvdd, ei, 2hump_ei,
/// 3hump_ei); RepRapFirmware's ei2/ei3/zvddd are accepted too.
struct ShaperSetting {
  std::string type;
  double freq_hz = 0;
  double damping = 0.1;
};

/// Kalico's nonlinear pressure advance ([extruder] options of Kalico's bleeding-edge-v2 branch,
/// klippy/kinematics/extruder.py PANonLinearModel and ExtruderStepper; the formula is in
/// klippy/chelper/kin_extruder.c and ident/flow_advance.hpp). Kalico's documentation (Nonlinear
/// Pressure Advance) named the offset `linear_offset` in earlier versions; its current source
/// reads `nonlinear_offset`, which is what is written.
struct KalicoAdvanceSetting {
  std::string model = "tanh";              ///< pressure_advance_model: tanh or recipr
  double linear_advance_s = 0;             ///< linear_advance (>= 0)
  double nonlinear_offset_mm = 0;          ///< nonlinear_offset (>= 0)
  double linearization_velocity_mm_s = 0;  ///< linearization_velocity (> 0 when the offset is)
  std::optional<double> time_offset_s;     ///< pressure_advance_time_offset (-0.2..0.2 s)
};

/// The design values to write. Unset values are left alone in the configuration.
struct CompensatorSettings {
  std::optional<double> pa_k_s;                ///< advance K, s (Kalico: ignored when `kalico` is set)
  std::optional<KalicoAdvanceSetting> kalico;  ///< Kalico only: the nonlinear model replaces pressure_advance
  std::optional<double> pa_smooth_s;  ///< the firmware's own smoothing time (Klipper smooth time, Marlin ADVANCE_TAU)
  std::map<std::string, ShaperSetting> shapers;  ///< by axis "x", "y" ("z": Klipper only)
  std::string klipper_extruder = "extruder";     ///< Klipper section holding pressure_advance
  int rrf_drive = 0;                             ///< RepRapFirmware extruder drive (M572 D)
  int extruder_index = 0;                        ///< Marlin: entry of a per-extruder ADVANCE_K list, M900 T
  /// Marlin build with FT_MOTION enabled (set by export from the configuration): shapers are
  /// FT_MOTION's (FTM_DEFAULT_SHAPER_X/Y ...), the classic shaper and smooth linear advance are
  /// bypassed.
  bool marlin_ft_motion = false;
  /// The running Marlin reported fixed-time motion active (its M493 report, runner.cpp): the
  /// runtime G-code is M493 (Marlin/src/gcode/feature/ft_motion/M493.cpp) instead of M593/M900,
  /// and a configuration without FT_MOTION is not the running build's: its classic lines are
  /// left alone.
  bool marlin_ft_motion_live = false;
  /// The letters of that M493 (marlin_m493.hpp: the form its report took); default the
  /// 2024-2025 axis_named form: S1, X/Y shaper 1-8, A/B frequency, I/J damping, P1 K advance.
  M493Syntax marlin_m493;
  /// The hot end's thermal model, written as the firmware's temperature control
  /// (thermal_export.hpp): Marlin's MPC, Kalico's MPC, Klipper's PID, RepRapFirmware's M307.
  std::optional<ThermalExport> thermal;
  /// Replaces the trailing comment of a line whose value changes (the old comment described
  /// the old value), e.g. "tunekit 2026-01-31: from step.json"; empty: comments are kept.
  std::string change_note;
};

/// One value set in the file.
struct ConfigChange {
  std::string key;        ///< e.g. "[extruder] pressure_advance", "ADVANCE_K", "M572 S"
  std::string old_value;  ///< empty when the line is new
  std::string new_value;
  std::size_t line = 0;  ///< 1-based line in the original file (0: appended)
  std::string where;     ///< "SAVE_CONFIG block", "section", "new section", "new line", ...
};

struct ExportResult {
  ExportFirmware firmware = ExportFirmware::klipper;
  std::string path;
  std::string original;
  std::string updated;
  std::string diff;  ///< unified diff original -> updated; empty when nothing changes
  std::vector<ConfigChange> changes;
  std::vector<std::string> warnings;
  /// What the user must also do for the firmware to use the new values (restart, M502 + M500, ...).
  std::vector<std::string> notes;
  std::string gcode;  ///< the same settings as runtime commands (Marlin adds M500)
  bool changed() const { return original != updated; }
  nlohmann::json to_json() const;  ///< everything but the file contents
};

/// Normalizes a shaper name to Klipper's spelling (lower case; ei2 -> 2hump_ei, ...).
std::string canonical_shaper_type(const std::string& type);
/// The firmware's name for a shaper; InputError when the firmware lacks it. `ft_motion`: Marlin's
/// FT_MOTION shapers instead of its classic ZV.
std::string firmware_shaper_name(ExportFirmware fw, const std::string& type, bool ft_motion = false);

/// Whether a Marlin Configuration_adv.h enables FT_MOTION (an uncommented `#define FT_MOTION`).
bool marlin_ft_motion_enabled(const std::string& configuration_text);

/// Checks every value against the firmware's accepted range and shaper types and throws one
/// InputError (exit 2) listing all violations.
void validate_settings(ExportFirmware fw, const CompensatorSettings& s);

/// Why a Z shaper is not exported for `fw` (one sentence), or empty for Klipper, which reads
/// shaper_type_z / shaper_freq_z / damping_ratio_z in [input_shaper] since its Z-axis input
/// shaper (Butyugin, October 2025).
std::string z_shaper_refusal(ExportFirmware fw);

/// Edits configuration text. `path` names the file in messages and the diff. Validates first.
ExportResult export_config_text(ExportFirmware fw, const std::string& text, const std::string& path,
                                const CompensatorSettings& s);
/// Reads `path` and edits it in memory (nothing is written).
ExportResult export_config_file(ExportFirmware fw, const std::string& path, const CompensatorSettings& s);

/// The smoothing time `fw` takes from a design: Klipper's pressure_advance_smooth_time is the
/// triangular window, or Klipper's default 0.040 s when that is longer (the design is a lower
/// bound: a shorter window than the default buys little and makes the extruder noisier); Marlin's ADVANCE_TAU is
/// designed with Marlin's own exponential cascade (ident/marlin_smoothing.hpp: the extra extruder acceleration of a
/// print acceleration step within the limit, at least one update period per stage; InputError beyond M900 U's 0.5 s);
/// RepRapFirmware has none. Rounded up to the written precision (0.1 ms) so that the
/// acceleration bound still holds. nullopt when the firmware has no such setting, or the design
/// has no window or a zero one.
std::optional<double> smoothing_time_for(ExportFirmware fw, const design::AdvanceDesign& d);

/// Flow-dependent advance as runtime commands, one per scheduled flow (for a slicer's
/// per-feature or per-speed G-code): SET_PRESSURE_ADVANCE, M900 K or M572, each with a comment
/// giving the flow. Empty for an empty schedule.
std::string advance_schedule_gcode(ExportFirmware fw, const std::vector<design::ScheduledAdvance>& schedule,
                                   const CompensatorSettings& s);

/// Writes an export result: backup of the current file, then atomic replacement. Returns the
/// backup's path, or an empty string (and touches nothing) when nothing changes.
std::string apply_export(const ExportResult& r, const std::function<void(const std::string&)>& before_rename = {});

}  // namespace tunekit::firmware
