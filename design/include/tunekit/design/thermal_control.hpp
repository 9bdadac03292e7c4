#pragma once
// Temperature controllers designed from the hot end's identified thermal model
// (ident/thermal_model.hpp): a PID for firmware without a model-based controller (Klipper), with
// the robustness of the loop it closes, and the first-order-plus-dead-time heater model
// RepRapFirmware's M307 holds.
//
// The PID follows Skogestad's SIMC rule for a second-order process with dead time (S. Skogestad,
// "Simple analytic rules for model reduction and PID controller tuning", Journal of Process
// Control 13, 2003, rule for tau2 > theta): the heater block is the dominant lag (gain k = P/A K
// per unit of duty, time constant tau1 = C/A), the sensor the second lag (tau2 = 1/R), and theta
// the control loop's own delay (sampling and the firmware's derivative smoothing). In series
// (cascade) form, with the closed-loop time constant tau_c:
//   Kc = tau1 / (k (tau_c + theta)),  tau_I = min(tau1, 4 (tau_c + theta)),  tau_D = tau2,
// converted to the parallel form the firmware runs. The default tau_c is the sensor's lag 1/R: the
// loop is made no faster than the sensor can see, a choice slower than SIMC's "tight" tau_c =
// theta and robust to the model's errors; the margins of the resulting loop are computed on the
// model (not read from a table) and returned with the gains.

#include <string>

#include "tunekit/ident/thermal_model.hpp"

namespace tunekit::design {

/// Choices of the PID design. Times in s.
struct ThermalPidOptions {
  /// Delay of the control loop itself. Klipper reads the sensor every 0.3 s (its ADC report time)
  /// and smooths the derivative over smooth_time (1 s by default): 0.3 + 1/2 = 0.8 s.
  double loop_delay_s = 0.8;
  /// Closed-loop time constant tau_c; not positive: the sensor's lag 1/R.
  double closed_loop_time_s = 0.0;
  /// Part-cooling fan duty the loop is designed at, [0, 1] (the ambient loss A + f (F - A)).
  double fan_duty = 0.0;
};

/// A PID in parallel form, u = kp e + ki integral(e) + kd de/dt (u the heater duty in [0, 1],
/// e in K), with the model it was designed on and the margins of the loop it closes.
struct ThermalPid {
  double kp_per_k = 0.0;            ///< duty per K
  double ki_per_k_s = 0.0;          ///< duty per K s
  double kd_s_per_k = 0.0;          ///< duty s per K
  double process_gain_k = 0.0;      ///< k = P / (A + f (F - A)), K per unit duty
  double block_time_s = 0.0;        ///< tau1 = C / (A + f (F - A))
  double sensor_time_s = 0.0;       ///< tau2 = 1 / R
  double loop_delay_s = 0.0;        ///< theta
  double closed_loop_time_s = 0.0;  ///< tau_c
  double gain_margin = 0.0;         ///< 1 / |L| where the loop's phase is -180 degrees
  double phase_margin_deg = 0.0;    ///< 180 + arg L where |L| = 1
  double max_sensitivity = 0.0;     ///< Ms = max |1 / (1 + L)| (SIMC's tight tuning gives about 1.6-1.7)
  std::string rule;                 ///< one sentence naming the rule and its choices
};

/// The SIMC PID for `m`. InputError when the model lacks a positive P, C, R or A, or the options
/// are out of range.
ThermalPid design_thermal_pid(const ident::ThermalModel& m, const ThermalPidOptions& o = {});

/// Klipper's pid_Kp, pid_Ki, pid_Kd: the parallel gains times 255 (klippy/extras/heaters.py,
/// PID_PARAM_BASE = 255, ControlPID divides each option by it; the derivative acts on the
/// measured temperature, the integral is clamped to max_power / Ki).
struct KlipperPidGains {
  double kp = 0.0, ki = 0.0, kd = 0.0;
};
inline constexpr double kKlipperPidParamBase = 255.0;
KlipperPidGains klipper_pid_gains(const ThermalPid& pid);

/// RepRapFirmware's heater model (M307 H R K D E S B, src/Heating/FOPDT.cpp of RepRapFirmware 3.5):
/// the heating rate at full PWM without cooling, the cooling rate at 100 K above ambient with the
/// fan off and the fan's additional cooling rate at 100 K with the fan on full (RRF 3.2 and later:
/// `K<fan off>:<fan on>`), the dead time and the cooling exponent,
///   dT/dt = R u - K ((T - Ta)/100)^E - K_fan f (T - Ta)/100.
struct RrfHeaterModel {
  double heating_rate_k_s = 0.0;      ///< R = P / C
  double cooling_rate_k_s = 0.0;      ///< K (fan off), K/s at 100 K rise
  double fan_cooling_rate_k_s = 0.0;  ///< K_fan: the fan's extra cooling at full duty, K/s at 100 K rise
  double dead_time_s = 0.0;           ///< D: the sensor's lag 1/R plus the loop's delay
  double cooling_exponent = 1.0;      ///< E
};

/// The RRF model of `m`. With exponent 1 (the default) the lumped model's linear loss is written
/// exactly: K = 100 A / C; another exponent E in [1, 1.6] matches the loss at `match_rise_k` above
/// ambient: K = (A / C) rise / (rise / 100)^E. The fan term is linear in RRF as in the model:
/// K_fan = 100 (F - A) / C. `loop_delay_s` is added to the sensor's lag in D (RRF's own tuning
/// measures D from the heater's switching, which includes the sensor's lag).
RrfHeaterModel rrf_heater_model(const ident::ThermalModel& m, double exponent = 1.0, double match_rise_k = 180.0,
                                double loop_delay_s = 0.0);

}  // namespace tunekit::design
