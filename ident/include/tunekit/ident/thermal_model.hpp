#pragma once
// The hot end's lumped thermal model: the parameters that identification estimates and that
// firmware/ writes as each firmware's model-predictive or PID temperature control.
//
// The model, as Marlin's model-predictive temperature control states it (Marlin's MPC
// documentation, 2022-2024): a heater block of heat capacity C (J/K) at temperature T_b driven
// by the heater's power u*P (u the PWM duty in [0, 1], P in W), losing heat to the ambient
// T_a through (A + f*(F - A)) (W/K, f the part-cooling fan's duty in [0, 1]) and to the
// filament that flows through it, H (J/K/mm) per millimetre of filament per second:
//
//   C dT_b/dt = u P - (A + f (F - A)) (T_b - T_a) - H v_e (T_b - T_a)
//   dT_s/dt   = R (T_b - T_s)
//
// with v_e the filament feed (mm/s) and T_s the sensor's reading, which follows the block with
// the responsiveness R (1/s). The fan loss may be non-linear in f; fan_transfer_w_per_k then
// gives it at full fan and the identification states how it interpolates.

namespace tunekit::ident {

/// One hot end's thermal parameters (SI units, temperatures in degC).
struct ThermalModel {
  double heater_power_w = 0.0;                     ///< P: heater power at full duty, W
  double block_heat_capacity_j_per_k = 0.0;        ///< C: heater block, nozzle and sensor, J/K
  double sensor_responsiveness_per_s = 0.0;        ///< R: rate the sensor follows the block, 1/s
  double ambient_transfer_w_per_k = 0.0;           ///< A: loss to the ambient with the fan off, W/K
  double fan_transfer_w_per_k = 0.0;               ///< F: loss to the ambient at full fan, W/K
  double filament_heat_capacity_j_per_k_mm = 0.0;  ///< H: heat taken per mm of filament and K
  double ambient_c = 25.0;                         ///< T_a: the ambient temperature, degC
};

}  // namespace tunekit::ident
