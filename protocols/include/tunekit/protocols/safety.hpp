#pragma once
// Checks a protocol's G-code against a machine profile before anything is sent: travel limits,
// per-axis speed and acceleration, extruder feed speed, volumetric flow and acceleration,
// temperatures, and the sensors the protocol needs. Every violation is listed, not just the first.

#include <string>
#include <vector>

#include "tunekit/protocols/machine_profile.hpp"

namespace tunekit::protocols {

struct Violation {
  std::size_t line = 0;  ///< 1-based line in the protocol's G-code (0: not tied to a line)
  std::string gcode;     ///< the offending line
  std::string what;      ///< e.g. "x speed 400 mm/s exceeds max_velocity_mm_s 300"
};

/// Interprets `gcode` from the machine's home position (axis minimums) and returns all
/// violations of `profile`'s limits; `sensors` lists sensors the protocol needs
/// ("accelerometer", "load_cell", "filament_encoder", "camera").
std::vector<Violation> check_protocol(const std::vector<std::string>& gcode, const MachineProfile& profile,
                                      const std::vector<std::string>& sensors);

/// Throws InputError (exit code 2) naming every violation when there is any.
void require_within_limits(const std::vector<std::string>& gcode, const MachineProfile& profile,
                           const std::vector<std::string>& sensors);

}  // namespace tunekit::protocols
