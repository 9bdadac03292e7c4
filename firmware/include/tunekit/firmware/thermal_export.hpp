#pragma once
// The hot end's thermal model (ident/thermal_model.hpp) as each firmware's temperature control,
// in its own names, units and bounds (docs/thermal.md, "Exporting the thermal model"):
//   Marlin MPC: Configuration.h MPC_HEATER_POWER, MPC_BLOCK_HEAT_CAPACITY,
//     MPC_SENSOR_RESPONSIVENESS, MPC_AMBIENT_XFER_COEFF, MPC_AMBIENT_XFER_COEFF_FAN255,
//     FILAMENT_HEAT_CAPACITY_PERMM (MPCTEMP enabled, PIDTEMP disabled) and `M306 E P C R A F H`
//     (Marlin 2.1.2-2.1.3: Marlin/Configuration.h, Marlin/src/gcode/temp/M306.cpp, whose report
//     prints P and C with 2 decimals, R, A, F and H with 4; F is the total loss at full fan).
//   Kalico: [extruder] control: mpc with heater_power, block_heat_capacity, sensor_responsiveness,
//     ambient_transfer, fan_ambient_transfer (a list at evenly spaced fan speeds, interpolated)
//     and filament_heat_capacity in J/(g K) (Kalico, klippy/extras/heaters.py and control_mpc.py:
//     heater_power, block_heat_capacity, sensor_responsiveness above 0, ambient_transfer >= 0,
//     filament_heat_capacity above 0 with filament_density (g/cm^3, default 1.2) and
//     filament_diameter (mm, default 1.75)).
//   Klipper: [extruder] control: pid, pid_kp, pid_ki, pid_kd (design/thermal_control.hpp, SIMC,
//     times PID_PARAM_BASE 255, klippy/extras/heaters.py; written with 3 decimals as
//     PID_CALIBRATE saves them).
//   RepRapFirmware: `M307 H<heater> R K<off>:<on> D E S B0` in config.g (src/Heating/FOPDT.cpp
//     SetParameters bounds: R/K >= 0.1, fan rate >= 0, 1 <= E <= 1.6, D > 0.0099, D K <= 50,
//     0.0099 < S <= 1; written with FOPDT.cpp's own decimals).

#include <optional>
#include <string>
#include <vector>

#include "tunekit/design/thermal_control.hpp"
#include "tunekit/ident/thermal_model.hpp"

namespace tunekit::firmware {

enum class ExportFirmware;

/// What is exported from a thermal identification, and how.
struct ThermalExport {
  ident::ThermalModel model;
  design::ThermalPidOptions pid;        ///< Klipper's PID design
  bool kalico_pid = false;              ///< Kalico: write the PID (control: pid) instead of its MPC
  int rrf_heater = 1;                   ///< RepRapFirmware heater number (M307 H)
  double rrf_cooling_exponent = 1.0;    ///< M307 E (design::rrf_heater_model)
  double rrf_max_pwm = 1.0;             ///< M307 S for a new line (an existing S is kept)
  double rrf_match_rise_k = 180.0;      ///< the rise above ambient the cooling rate is matched at when E != 1
  double filament_density_g_cm3 = 1.2;  ///< Kalico's filament_density (its default) for filament_heat_capacity
  double filament_diameter_mm = 1.75;   ///< Kalico's filament_diameter (its default)
  int kalico_fan_breakpoints = 3;       ///< entries of fan_ambient_transfer (Kalico's default 3: 0/50/100 %)
};

/// One option of a Klipper-style section, as written ("numeric" values compare by number).
struct ThermalOption {
  std::string option, value;
  bool numeric = false;
  double number = 0.0;
  int decimals = 0;
};

/// One Marlin define and its value.
struct MarlinThermalDefine {
  std::string name;
  double value = 0.0;
  int decimals = 0;
};

/// The [extruder] options for Klipper (PID) or Kalico (MPC, or PID with kalico_pid).
std::vector<ThermalOption> thermal_klipper_options(ExportFirmware fw, const ThermalExport& t);
/// The runtime G-code: Kalico's MPC_SET for the MPC; empty for a PID (Klipper has no command that
/// sets PID gains: the configuration is read at RESTART).
std::string thermal_klipper_gcode(ExportFirmware fw, const ThermalExport& t, const std::string& section);

/// Marlin's MPC defines in Configuration.h, and the M306 line of the same values.
std::vector<MarlinThermalDefine> marlin_mpc_defines(const ThermalExport& t);
std::string marlin_m306_gcode(const ThermalExport& t, int extruder);

/// RepRapFirmware's M307 parameters as written, by letter (R, K, D, E), from the model.
struct RrfM307Values {
  std::string r, k, d, e;
};
RrfM307Values rrf_m307_values(const ThermalExport& t);

/// Appends to `bad` every value the firmware would refuse (or that is not a positive number), in
/// the firmware's words with its source, as the values are written.
void validate_thermal(ExportFirmware fw, const ThermalExport& t, std::vector<std::string>& bad);

}  // namespace tunekit::firmware
