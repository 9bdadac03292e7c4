#pragma once
// A machine profile: what a printer can safely do and which sensors it has, read from TOML.
// Every experiment protocol is checked against it before the first byte is sent, and the
// compensator design reads the extruder and print limits from it. Units are in the key
// names (mm, mm/s, mm/s^2, mm^3/s, degC). See datasets/machines/sim.toml for a complete file.

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace tunekit::machine {

struct AxisLimits {
  double min_mm = 0;
  double max_mm = 0;
  double max_velocity_mm_s = 0;
  double max_accel_mm_s2 = 0;
};

struct ExtruderLimits {
  double filament_diameter_mm = 1.75;
  double nozzle_diameter_mm = 0.4;
  double max_flow_mm3_s = 0;     ///< volumetric flow limit of the hot end
  double max_velocity_mm_s = 0;  ///< filament feed speed limit
  double max_accel_mm_s2 = 0;    ///< filament acceleration limit (the extruder motor)
  /// Longest extrude-only move the firmware accepts, mm (Klipper's max_extrude_only_distance,
  /// default 50 mm); protocols split longer feeds into moves of at most this length.
  double max_extrude_only_distance_mm = 50;
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
  /// Klipper: the accelerometer chip (adxl345, lis2dw, lis3dh, mpu9250, mpu6050, icm20948,
  /// bmi160; `accelerometer = "lis2dw"` in the profile) and its config section name
  /// (`accelerometer_name = "lis2dw toolhead"`; default: the chip name, i.e. `[adxl345]`).
  std::string accelerometer_chip = "adxl345";
  std::string accelerometer_name;
  /// Klipper: the load cell's config section name (`[load_cell]` or `[load_cell NAME]`).
  std::string load_cell_name = "load_cell";
};

/// The machine's own settings that the protocols change for a test and restore after it (also
/// on abort): table [firmware_state]. Defaults are the firmwares' defaults (firmware_limits.hpp).
struct FirmwareState {
  /// Input shaper configured on the machine per axis, "type:freq_hz:damping" in the firmware's
  /// spelling; empty when the machine has none configured (then nothing is turned off).
  std::map<std::string, std::string> shaper;
  double minimum_cruise_ratio = 0.5;  ///< Klipper [printer] minimum_cruise_ratio
  double steps_per_mm_x = 80;         ///< Marlin M92 X (sizes the sweep above MIN_STEPS_PER_SEGMENT)
  double steps_per_mm_y = 80;         ///< Marlin M92 Y
  double min_segment_time_s = 0.020;  ///< Marlin M205 B (DEFAULT_MINSEGMENTTIME), s
  double max_accel_xy_mm_s2 = 3000;   ///< Marlin/RRF M201 X/Y, mm/s^2
  double retract_accel_mm_s2 = 3000;  ///< Marlin M204 R (moves without X/Y/Z steps), mm/s^2
  double max_accel_e_mm_s2 = 3000;    ///< RRF M201 E, mm/s^2
  double jerk_xy_mm_s = 15;           ///< RRF M566 X/Y (instantaneous speed change), mm/s
  /// Klipper: the acceleration in force (toolhead max_accel) when the machine was identified,
  /// mm/s^2, restored after a test; 0 when not known (then [print] max_accel_mm_s2 is restored).
  double accel_in_force_mm_s2 = 0;
  /// Marlin with FT_MOTION: its answer to M493 (and to M493 V), line by line as printed
  /// (firmware/marlin_m493.hpp), so that a dry run shows the M493 lines that turn its shaper off
  /// for a test and set it back; a live run reads the report again on connecting.
  std::vector<std::string> m493_report;
};

/// The physical ranges of a profile's limits: a value beyond is a typing error (a travel of a
/// kilometre, a hot end at 1e9 degC), and the gate checks protocols against these limits.
/// parse_machine_profile() refuses a profile beyond them; the firmware-configuration importers
/// (profile_import.hpp) check what they read against the same ranges.
namespace profile_limits {
inline constexpr double kMaxTravel_mm = 10000;       ///< |min_mm|, |max_mm|: 10 m, beyond any printer's axis
inline constexpr double kMaxSpeed_mm_s = 10000;      ///< 10 m/s
inline constexpr double kMaxAccel_mm_s2 = 1e6;       ///< 100 g
inline constexpr double kMaxHotend_c = 600;          ///< above any polymer's processing temperature (PEEK: 400-450)
inline constexpr double kMaxBed_c = 400;             ///< PEEK-class chambers and beds stay below
inline constexpr double kMaxFilament_mm = 10;        ///< filament and nozzle diameters, line sizes: 1.75, 2.85 ...
inline constexpr double kMaxFlow_mm3_s = 2000;       ///< large-format pellet extruders reach a few hundred
inline constexpr double kMaxSampleRate_hz = 100000;  ///< accelerometer sample rate
}  // namespace profile_limits

/// True for the accelerometer chips Klipper's API server streams (see klipper_sensors.hpp).
bool is_klipper_accelerometer_chip(const std::string& chip);
/// "adxl345, lis2dw, ..." for messages.
std::string klipper_accelerometer_chips();

/// [belts]: the two CoreXY belt paths as `tunekit belts` measures them (optional section).
struct BeltSettings {
  std::string belt;                ///< belt type, e.g. "gt2-6mm" (empty: not given)
  double mass_g_m = 0;             ///< the belt's linear mass, g/m (0: from `belt`)
  double span_mm = 0;              ///< free span plucked, between the contact points, mm (0: not given)
  double span_uncertainty_mm = 0;  ///< standard uncertainty of the span, mm (0: not given)
  double target_n = 0;             ///< tension to set, N (0: not given)
};

struct MachineProfile {
  std::string name;
  std::string id;                          ///< the machine's id in the calibration history (may be empty)
  std::string kinematics = "cartesian";    ///< cartesian, corexy, delta
  std::string firmware;                    ///< marlin, klipper, rrf, prusa (may be empty: ask M115)
  std::map<std::string, AxisLimits> axes;  ///< "x", "y", "z"
  ExtruderLimits extruder;
  PrintSettings print;
  TemperatureLimits temperature;
  Sensors sensors;
  FirmwareState state;
  BeltSettings belts;
  /// [network] http = "http://HOST[:PORT]": RepRapFirmware's web server, through which tunekit
  /// fetches the accelerometer files M956 writes (rrf_http.hpp; RepRapFirmware cannot send a
  /// file over USB serial). Empty: serial only.
  std::string http_address;
  /// [network] password: the web server's password (M551), if it has one. The environment
  /// variable TUNEKIT_RRF_PASSWORD wins over it (rrf_password); tunekit never prints it.
  std::string http_password;
  std::string source_path;
  /// Where each value came from, by profile key ("axes.x.max_accel_mm_s2", "extruder.max_flow_mm3_s"):
  /// "printer.cfg:14 [printer] max_accel: 3000", a firmware's default with its formula, or
  /// tunekit's default with its reason. Filled by the firmware-configuration importers
  /// (profile_import.hpp); empty for a TOML profile.
  std::map<std::string, std::string> sources;

  /// Filament cross-section area, mm^2.
  double filament_area_mm2() const;
  /// Line cross-section (rectangle approximation, width x layer height), mm^2.
  double line_area_mm2() const;
  const AxisLimits& axis(const std::string& name) const;  ///< throws InputError if absent
};

/// Reads a profile; throws InputError (exit 2) with FILE:LINE for syntax errors, missing
/// required keys, non-positive limits, or unknown kinematics. The file may also be a firmware
/// configuration (a Klipper printer.cfg, a Marlin M503 report or Configuration.h, a
/// RepRapFirmware config.g), recognized by its content and imported (profile_import.hpp).
/// With `bytes`, the file's bytes as they were read and parsed are stored there (for its digest).
MachineProfile load_machine_profile(const std::string& path, std::string* bytes = nullptr);
MachineProfile parse_machine_profile(const std::string& toml_text, const std::string& path_for_messages);

}  // namespace tunekit::machine
