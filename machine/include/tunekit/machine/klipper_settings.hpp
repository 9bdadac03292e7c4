#pragma once
// What a Klipper machine reports about itself over its API server before a protocol is built
// (O'Connor et al., Klipper 3D printer firmware, docs/API_Server.md and docs/Status_Reference.md,
// 2025-2026): `info` (state, software version) and `objects/query` of the configuration in
// force (configfile.settings: every option a module read, defaults included) and of the live
// toolhead and extruder status. The limits the protocols must respect come from here, combined
// with the machine profile's by taking the stricter of the two (with_klipper_settings).

#include <limits>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::machine {

inline constexpr double kNotReported = std::numeric_limits<double>::quiet_NaN();

/// Values Klipper reports; NaN (kNotReported) where the machine did not report the option.
struct KlipperSettings {
  std::string state;                                     ///< info.state: "ready", "startup", "shutdown", "error"
  std::string state_message;                             ///< info.state_message
  std::string software_version;                          ///< info.software_version
  double max_velocity_mm_s = kNotReported;               ///< toolhead status max_velocity (live), mm/s
  double max_accel_mm_s2 = kNotReported;                 ///< toolhead status max_accel (live), mm/s^2
  double minimum_cruise_ratio = kNotReported;            ///< toolhead status minimum_cruise_ratio (live)
  double square_corner_velocity_mm_s = kNotReported;     ///< toolhead status square_corner_velocity, mm/s
  double max_extrude_only_velocity_mm_s = kNotReported;  ///< [extruder] max_extrude_only_velocity, filament mm/s
  double max_extrude_only_accel_mm_s2 = kNotReported;    ///< [extruder] max_extrude_only_accel, filament mm/s^2
  double max_extrude_only_distance_mm = kNotReported;    ///< [extruder] max_extrude_only_distance, mm
  double pressure_advance_s = kNotReported;              ///< extruder status pressure_advance (live), s
  double smooth_time_s = kNotReported;                   ///< extruder status smooth_time (live), s
  /// [input_shaper] per axis with a non-zero frequency: "type:freq_hz:damping" (as the profile's
  /// [firmware_state] shaper spells it).
  std::map<std::string, std::string> shaper;
};

/// The `objects/query` parameters that fetch what parse_klipper_settings reads.
nlohmann::json klipper_settings_query();
/// Reads `info`'s result and `objects/query`'s result ({"status": {...}}).
KlipperSettings parse_klipper_settings(const nlohmann::json& info, const nlohmann::json& query);

/// The profile with the stricter of its own and Klipper's limits (extruder feed, acceleration
/// and extrude-only distance) and Klipper's state in force (minimum_cruise_ratio, input shaper)
/// as what the protocols restore after a test. Each change is described in `notes`.
MachineProfile with_klipper_settings(const MachineProfile& profile, const KlipperSettings& k,
                                     std::vector<std::string>& notes);

}  // namespace tunekit::machine
