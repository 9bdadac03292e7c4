#pragma once
// A machine profile: what a printer can safely do and which sensors it has, read from TOML.
// Every experiment protocol is checked against it before the first byte is sent, and the
// compensator design reads the extruder and print limits from it. Units are in the key
// names (mm, mm/s, mm/s^2, mm^3/s, degC). See datasets/machines/sim.toml for a complete file.

#include <map>
#include <optional>
#include <string>

namespace tunekit::protocols {

struct AxisLimits {
  double min_mm = 0;
  double max_mm = 0;
  double max_velocity_mm_s = 0;
  double max_accel_mm_s2 = 0;
};

struct ExtruderLimits {
  double filament_diameter_mm = 1.75;
  double nozzle_diameter_mm = 0.4;
  double max_flow_mm3_s = 0;      ///< volumetric flow limit of the hot end
  double max_velocity_mm_s = 0;   ///< filament feed speed limit
  double max_accel_mm_s2 = 0;     ///< filament acceleration limit (the extruder motor)
};

struct PrintSettings {
  double max_accel_mm_s2 = 0;  ///< the highest print acceleration used in production
  double line_width_mm = 0.45;
  double layer_height_mm = 0.2;
  double speed_mm_s = 60;
};

struct TemperatureLimits {
  double hotend_max_c = 0;
  double bed_max_c = 0;
  bool heaters_off_on_abort = true;
};

struct Sensors {
  bool accelerometer = false;
  bool load_cell = false;
  bool filament_encoder = false;
  bool camera = false;
  double accelerometer_rate_hz = 3200;
};

struct MachineProfile {
  std::string name;
  std::string id;                        ///< the machine's id in the calibration history (may be empty)
  std::string kinematics = "cartesian";  ///< cartesian, corexy, delta
  std::string firmware;                  ///< marlin, klipper, rrf, prusa (may be empty: ask M115)
  std::map<std::string, AxisLimits> axes;  ///< "x", "y", "z"
  ExtruderLimits extruder;
  PrintSettings print;
  TemperatureLimits temperature;
  Sensors sensors;
  std::string source_path;

  /// Filament cross-section area, mm^2.
  double filament_area_mm2() const;
  /// Line cross-section (rectangle approximation, width x layer height), mm^2.
  double line_area_mm2() const;
  const AxisLimits& axis(const std::string& name) const;  ///< throws InputError if absent
};

/// Parses a profile; throws InputError (exit 2) with FILE:LINE for syntax errors, missing
/// required keys, non-positive limits, or unknown kinematics.
MachineProfile load_machine_profile(const std::string& path);
MachineProfile parse_machine_profile(const std::string& toml_text, const std::string& path_for_messages);

}  // namespace tunekit::protocols
