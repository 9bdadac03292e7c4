#pragma once
// Marlin's smooth linear advance (SMOOTH_LIN_ADVANCE, M900 U / ADVANCE_TAU): the smoothing
// time designed with Marlin's own filter, not a box window (docs/export.md).
//
// What Marlin does (Marlin/src/module/stepper.cpp, Stepper::smooth_lin_adv_isr(), run every
// 1/SMOOTH_LIN_ADV_HZ seconds, 1000 Hz by default in Configuration_adv.h):
//   1. it looks ADVANCE_TAU ahead into the planner and takes the planned extruder step rate
//      there, times K: the target advance (steps);
//   2. it differentiates the target advance (difference times SMOOTH_LIN_ADV_HZ): the advance
//      step rate, which for a print acceleration step is a step of K * r * a;
//   3. it passes that rate through SMOOTH_LIN_ADV_EXP_ORDER first-order exponential smoothers
//      in series ("Approximate Gaussian smoothing via higher order exponential smoothing"),
//      each y += alpha * (x - y);
//   4. it adds the smoothed rate to the planned rate and steps the extruder at the sum.
// Looking ahead by tau centres the cascade, whose mean delay is tau. Each stage's factor is
// alpha = 1 - exp(-N / (tau * f)): the time constant tau/N per stage, as in Marlin's FT_MOTION
// smoothing (Marlin/src/module/ft_motion/smoothing.cpp, alpha = 1 - exp(-Ts * order / s_time)).
//
// Extra extruder acceleration: a print acceleration step a (mm/s^2 of the toolhead) makes the
// advance rate a step of K * r * a (mm/s of filament per s); after the cascade its slope is
// K * r * a * f * max_n h[n], h the cascade's discrete impulse response
// h[n] = alpha^N * C(n+N-1, N-1) * (1-alpha)^n. For large tau*f this tends to
// c(N) * K * r * a / tau with c(N) = N (N-1)^(N-1) e^-(N-1) / (N-1)! (the peak of the Erlang
// density with mean tau; c(1) = 1, c(5) = 0.977, growing as sqrt(N / 2 pi)).
// A reversal of the print acceleration (+a to -a) doubles the step.

#include <string>
#include <vector>

namespace tunekit::design {

/// Marlin's smoothing filter as built: SMOOTH_LIN_ADV_EXP_ORDER stages updated at
/// SMOOTH_LIN_ADV_HZ.
struct MarlinSmoothingFilter {
  int order = 5;              ///< SMOOTH_LIN_ADV_EXP_ORDER, exponential stages in series
  double update_hz = 1000.0;  ///< SMOOTH_LIN_ADV_HZ (Configuration_adv.h default)
};

/// Per-stage factor alpha = 1 - exp(-order / (tau_s * update_hz)). InputError for tau_s <= 0.
double marlin_smoothing_alpha(double tau_s, const MarlinSmoothingFilter& filter = {});

/// Peak slope of the cascade's unit-step response, 1/s: update_hz * max_n h[n]. A print
/// acceleration step a then gives an extra extruder acceleration K * r * a times this.
double marlin_smoothing_peak_slope_per_s(double tau_s, const MarlinSmoothingFilter& filter = {});

/// c(N): tau times the peak slope in the continuous limit (tau * update_hz -> infinity).
double marlin_smoothing_continuous_peak_factor(int order);

/// Marlin's documented bounds for ADVANCE_TAU.
/// M900 U accepts 0 to 0.5 s (Marlin/src/gcode/feature/advance/M900.cpp, WITHIN(tau, 0, 0.5)).
inline constexpr double kMarlinTauMax_s = 0.5;

struct MarlinTauDesign {
  double tau_s = 0;                      ///< ADVANCE_TAU to write (multiple of resolution_s)
  double required_tau_s = 0;             ///< shortest tau meeting the limit, before the floor
  double floor_tau_s = 0;                ///< order / update_hz: one update period per stage
  double extra_accel_per_box_mm_s2 = 0;  ///< extra extruder acceleration at tau_s / limit (<= 1)
  std::vector<std::string> notes;
};

/// Shortest ADVANCE_TAU (a multiple of resolution_s, rounded up) whose extra extruder
/// acceleration for a print acceleration step stays within the extruder's limit.
/// `box_window_s` = K * r * a / a_extruder_max: the requirement is
/// peak_slope(tau) <= 1 / box_window_s. Never below one update period per stage
/// (order / update_hz; shorter, each stage passes its input in one update and nothing is
/// smoothed). InputError when box_window_s is not positive and finite, or the design needs
/// more than Marlin's 0.5 s (the extruder cannot follow K at that acceleration).
MarlinTauDesign design_marlin_advance_tau(double box_window_s, const MarlinSmoothingFilter& filter = {},
                                          double resolution_s = 1e-4);

}  // namespace tunekit::design
