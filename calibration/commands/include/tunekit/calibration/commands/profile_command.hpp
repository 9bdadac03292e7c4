#pragma once
// tunekit profile as a function: a machine profile from the firmware configuration a printer
// already has (a Klipper printer.cfg with its includes and SAVE_CONFIG block, a Marlin M503 report
// or Configuration.h, a RepRapFirmware config.g; machine/profile_import.hpp), written as a complete
// TOML machine profile in which every value names its source (the file and line, the firmware's
// default and its formula, or tunekit's default and its reason), or as JSON. The shape of a command
// is described in docs/cpp-api.md.

#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::calibration {

struct ProfileOptions {
  std::string file;                  ///< the firmware configuration (or a TOML profile, checked and rewritten)
  std::string output_toml;           ///< write the TOML profile here (atomically); empty: print it
  std::vector<std::string> sensors;  ///< accelerometer, load_cell, camera, filament_encoder: declared
  std::vector<double> travel_mm;     ///< M503 only: X, Y, Z travel from 0, mm
  double hotend_max_c = 0;           ///< M503 only: highest hot-end target, degC (0: not given)
  double bed_max_c = 0;              ///< M503 only: highest bed target, degC (0: not given)
};

struct ProfileOutcome {
  ProfileOptions options;
  InputDigest input;   ///< the configuration file named on the command line
  std::string format;  ///< "klipper", "marlin-m503", "marlin-configuration", "rrf", "toml"
  machine::MachineProfile profile;
  std::string toml;  ///< the profile as TOML (machine::machine_profile_toml)
};

/// Imports the file and renders the profile (writing it to output_toml when given). InputError
/// (exit 2) located FILE:LINE for what the configuration lacks or holds that is not usable.
ProfileOutcome compute_profile(const ProfileOptions& options);

/// The envelope: results format, kinematics, firmware, axes {x,y,z: {min_mm, max_mm,
/// max_velocity_mm_s, max_accel_mm_s2}}, extruder, print, temperature, sensors, firmware_state and
/// sources (profile key -> where the value came from).
Envelope to_envelope(const ProfileOutcome& outcome);
/// The TOML profile (or, when it was written to a file, one line saying where).
void print_text(const ProfileOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
