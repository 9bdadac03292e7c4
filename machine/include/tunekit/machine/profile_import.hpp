#pragma once
// Machine profiles from the firmware configurations users have: a Klipper printer.cfg (with its
// [include]s and its SAVE_CONFIG block), a Marlin M503 report or Configuration.h (with
// Configuration_adv.h beside it), a RepRapFirmware config.g. Each importer computes the limits
// the firmware itself computes from the file, defaults included, and names the source of every
// value in MachineProfile::sources (key: the profile key, e.g. "axes.x.max_accel_mm_s2"; value:
// "printer.cfg:14 [printer] max_accel: 3000", or the firmware default and its formula, or
// tunekit's conservative default and its reason for what no firmware configuration holds).
// machine::load_machine_profile() reads all of these as well as TOML profiles (the format is
// recognized by the file's content). Errors are InputError (exit 2) located FILE:LINE.
//
// Sources: Kevin O'Connor et al., Klipper 3D printer firmware (klippy/configfile.py,
// klippy/toolhead.py, klippy/stepper.py, klippy/kinematics/{extruder,cartesian,corexy,delta}.py),
// 2016-2026; MarlinFirmware, Marlin 2.1 (Marlin/src/module/planner.cpp, Configuration.h,
// Configuration_adv.h), 2011-2026; Duet3D, RepRapFirmware 3.5 G-code dictionary, 2013-2026.

#include <string>
#include <vector>

#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::machine {

enum class ConfigFormat {
  profile_toml,   ///< tunekit's own machine profile (TOML)
  klipper,        ///< Klipper printer.cfg (INI dialect with [sections])
  marlin_m503,    ///< the answer Marlin prints to M503 (M92, M203, M201, M204, ... lines)
  marlin_config,  ///< Marlin's Configuration.h (#define lines)
  rrf,            ///< RepRapFirmware config.g (G-code with M208, M669, M584, ...)
};

/// "toml", "klipper", "marlin-m503", "marlin-configuration", "rrf".
std::string to_string(ConfigFormat f);

/// The format of `text` by its content (the file name only breaks ties): `#define` lines are
/// Configuration.h, `[section]` headers with `key: value` options Klipper, a TOML profile has
/// [machine] and `key = value` lines, M-code lines are M503 (with an `echo:` prefix or M92/M203
/// without M208/M584/M669) or config.g. InputError for an empty file or one of none of these.
ConfigFormat detect_config_format(const std::string& text, const std::string& path);

/// Options for the importers.
struct ProfileImportOptions {
  /// Sensors to declare that the configuration does not list: "accelerometer", "load_cell",
  /// "camera", "filament_encoder" (`tunekit profile --sensor`).
  std::vector<std::string> sensors;
  /// An M503 report holds no travel: give the X, Y and Z travel (mm, from 0) here
  /// (`tunekit profile --travel X,Y,Z`); without it an M503 report is refused, naming what is missing.
  std::vector<double> travel_mm;
  /// Nor the heaters' limits: the highest hot-end and bed targets, degC (`--hotend-max-c`,
  /// `--bed-max-c`; 0: not given).
  double hotend_max_c = 0;
  double bed_max_c = 0;
};

/// Klipper printer.cfg: [include] (globs relative to the including file, nested, sorted; a
/// missing non-glob include or an include loop is an error) and the SAVE_CONFIG block (its
/// options apply where the regular part does not set them, as klippy/configfile.py loads it).
MachineProfile profile_from_klipper(const std::string& path, const ProfileImportOptions& options = {});
/// Marlin: an M503 report or Configuration.h (+ Configuration_adv.h in the same folder).
MachineProfile profile_from_marlin(const std::string& path, const ProfileImportOptions& options = {});
/// RepRapFirmware config.g (the file itself: macros it calls with M98 are not read).
MachineProfile profile_from_rrf(const std::string& path, const ProfileImportOptions& options = {});

/// Any supported file: a TOML profile (parse_machine_profile; sources stay empty) or a firmware
/// configuration (the importer of its format), returned as load_machine_profile() reads the TOML
/// machine_profile_toml() writes of it: the same checks and defaults as every TOML profile, with
/// the sources kept. With `bytes`, the file's bytes as read are stored there (the importers of
/// firmware configurations read the file, and the files it includes, themselves).
MachineProfile import_machine_profile(const std::string& path, const ProfileImportOptions& options = {},
                                      std::string* bytes = nullptr);

/// Whether the file at `path` (the first bytes are read) is a firmware configuration rather than a
/// TOML profile; false when it cannot be read (the TOML reader then reports why).
bool is_firmware_configuration(const std::string& path);

/// The profile as a complete TOML machine profile that load_machine_profile() reads back, every
/// value with its source as a `# ...` comment (from `sources`; values without one say so).
std::string machine_profile_toml(const MachineProfile& profile);

}  // namespace tunekit::machine
