// Marlin's smooth linear advance (ADVANCE_TAU) designed with Marlin's own filter, checked
// against a step-by-step simulation of that filter written from Marlin's source:
//   Marlin/src/module/stepper.cpp, Stepper::smooth_lin_adv_isr() (bugfix-2.1.x, 2025):
//     stepper_ticks = extruder_advance_tau_ticks + curr_timer_tick      (look ADVANCE_TAU ahead)
//     target_adv_steps = K * smooth_lin_adv_lookahead(stepper_ticks)   (planned E rate there)
//     la_step_rate = (target_adv_steps - last_target_adv_steps) * SMOOTH_LIN_ADV_HZ
//     for i < SMOOTH_LIN_ADV_EXP_ORDER: smoothed_vals[i] += alpha * (la_step_rate - smoothed_vals[i]);
//                                        la_step_rate = smoothed_vals[i]
//       ("Approximate Gaussian smoothing via higher order exponential smoothing")
//     set_la_interval(la_step_rate + planned_step_rate)                (extruder rate)
//   Marlin/Configuration_adv.h, SMOOTH_LIN_ADVANCE block: SMOOTH_LIN_ADV_HZ 1000, ADVANCE_TAU 0.02,
//     "ADVANCE_TAU is also the time ahead that the smoother needs to look into the planner";
//     "For k=0.04 at 10k acceleration and an "Orbiter 2" extruder it can be as low as 0.0075".
//   Marlin/src/gcode/feature/advance/M900.cpp: U accepted WITHIN(tau, 0.0f, 0.5f).
// The per-stage factor alpha = 1 - exp(-order / (tau f)) follows Marlin's FT_MOTION smoothing
// (Marlin/src/module/ft_motion/smoothing.cpp: alpha = 1 - expf(-(FTM_TS) * (FTM_SMOOTHING_ORDER) / s_time)).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <catch2/catch.hpp>

#include "tunekit/core/error.hpp"
#include "tunekit/design/marlin_smoothing.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/firmware/firmware_export.hpp"

using namespace tunekit;

namespace {

struct MarlinLaRun {
  double peak_extra_accel = 0;  ///< max |d/dt smoothed advance rate|, mm/s^2 of filament
  double final_advance = 0;     ///< integral of the smoothed advance rate at the end, mm
};

/// Toolhead speed of a trapezoid: accelerate at a to v, cruise, decelerate to 0.
double trapezoid_speed(double t, double a, double v, double cruise_s) {
  const double ta = v / a;
  if (t <= 0) return 0;
  if (t < ta) return a * t;
  if (t < ta + cruise_s) return v;
  if (t < 2 * ta + cruise_s) return v - a * (t - ta - cruise_s);
  return 0;
}

/// The ISR of stepper.cpp run at f Hz over a trapezoid; E rate = r * toolhead speed.
MarlinLaRun run_marlin_la(double k, double r, double a, double v, double cruise_s, double tau, int order, double f,
                          bool stop_after_cruise) {
  const double alpha = 1.0 - std::exp(-order / (tau * f));
  std::vector<double> smoothed(static_cast<std::size_t>(order), 0.0);
  double last_target = 0, last_out = 0, advance = 0;
  MarlinLaRun out;
  const double end = stop_after_cruise ? 2 * v / a + cruise_s + 1.0 : v / a + cruise_s;
  const long n = static_cast<long>((end + 0.5) * f);  // from half a second before the move
  for (long i = 0; i <= n; ++i) {
    // The planner time ADVANCE_TAU ahead of this update (the move starts on an update).
    const double ahead = -0.5 + static_cast<double>(i) / f;
    const double e_rate_ahead =
        r * trapezoid_speed(stop_after_cruise ? ahead : std::min(ahead, v / a + cruise_s / 2), a, v, cruise_s);
    const double target = k * e_rate_ahead;
    double rate = (target - last_target) * f;
    last_target = target;
    for (auto& s : smoothed) {
      s += alpha * (rate - s);
      rate = s;
    }
    out.peak_extra_accel = std::max(out.peak_extra_accel, std::abs(rate - last_out) * f);
    last_out = rate;
    advance += rate / f;
  }
  out.final_advance = advance;
  return out;
}

}  // namespace

TEST_CASE("Marlin ADVANCE_TAU: the designed tau keeps a simulated Marlin filter within the extruder's limit") {
  // A 0.45 x 0.2 mm line from 1.75 mm filament, K 0.05 s, 3000 mm/s^2, a weak extruder
  // (limit 400 mm/s^2): the limit, not the 5 ms floor, sets tau (about 14 ms).
  const double k = 0.05, a = 3000, v = 150, r = 0.45 * 0.2 / (std::numbers::pi / 4 * 1.75 * 1.75), lim = 400;
  const double box = design::min_smoothing_window_s(k, a, r, lim);
  const auto d = design::design_marlin_advance_tau(box);
  const design::MarlinSmoothingFilter marlin;  // 5 stages at SMOOTH_LIN_ADV_HZ 1000
  REQUIRE(d.tau_s > d.floor_tau_s);            // the limit, not the floor, sets tau here
  // A long cruise: the acceleration step is the worst case (each phase longer than tau).
  const auto at = run_marlin_la(k, r, a, v, 0.5, d.tau_s, marlin.order, marlin.update_hz, true);
  CHECK(at.peak_extra_accel <= lim * (1 + 1e-9));
  CHECK(at.peak_extra_accel > 0.95 * lim);  // and not far below it: the shortest such tau
  // One written step (0.1 ms) shorter exceeds the limit.
  const auto shorter = run_marlin_la(k, r, a, v, 0.5, d.tau_s - 1e-4, marlin.order, marlin.update_hz, true);
  CHECK(shorter.peak_extra_accel > lim);
  // The model's peak is the simulation's.
  CHECK(design::marlin_smoothing_peak_slope_per_s(d.tau_s) * k * r * a == Approx(at.peak_extra_accel).epsilon(1e-6));
  // Smoothing moves the advance in time but keeps it: at cruise the extruder is K r v ahead.
  const auto held = run_marlin_la(k, r, a, v, 0.5, d.tau_s, marlin.order, marlin.update_hz, false);
  CHECK(held.final_advance == Approx(k * r * v).epsilon(1e-6));
}

TEST_CASE("Marlin ADVANCE_TAU: the cascade's peak tends to the Erlang peak, and the documented range holds") {
  // Continuous limit c(N) = N (N-1)^(N-1) e^-(N-1) / (N-1)!: 1 for one stage (a plain
  // exponential, peak 1/tau), 0.977 for five.
  CHECK(design::marlin_smoothing_continuous_peak_factor(1) == Approx(1.0));
  CHECK(design::marlin_smoothing_continuous_peak_factor(5) == Approx(5 * 256 * std::exp(-4.0) / 24));
  const double tau = 0.2;  // 200 updates: near the continuous limit
  const auto sim = run_marlin_la(1.0, 1.0, 1.0, 1.0, 2.0, tau, 5, 1000, true);
  CHECK(sim.peak_extra_accel * tau == Approx(design::marlin_smoothing_continuous_peak_factor(5)).epsilon(0.02));
  // Marlin's own example (Configuration_adv.h): K 0.04 at 10000 mm/s^2 can run "as low as
  // 0.0075" s; with a 0.45 x 0.2 mm line from 1.75 mm filament that is an extruder limit near
  // 2000 mm/s^2, and the design lands in the same few milliseconds.
  const double r = 0.45 * 0.2 / (std::numbers::pi / 4 * 1.75 * 1.75);
  const auto orbiter = design::design_marlin_advance_tau(design::min_smoothing_window_s(0.04, 10000, r, 2000));
  CHECK(orbiter.tau_s >= 0.005);
  CHECK(orbiter.tau_s <= 0.010);
  // A tiny K: one update period per stage (5 ms at 1000 Hz) is the floor, with a note.
  const auto tiny = design::design_marlin_advance_tau(1e-5);
  CHECK(tiny.tau_s == Approx(0.005));
  CHECK(tiny.required_tau_s < tiny.tau_s);
  // Beyond M900 U's 0.5 s the design is refused with the reason.
  CHECK_THROWS_WITH(design::design_marlin_advance_tau(0.6), Catch::Contains("0.5"));
  CHECK_THROWS_AS(design::design_marlin_advance_tau(0), InputError);
}

TEST_CASE("Marlin export writes the cascade's ADVANCE_TAU, not the box window") {
  design::AdvanceDesign d;
  d.k_s = 0.05;
  d.window_box_s = 0.0093;
  const auto tau = firmware::smoothing_time_for(firmware::ExportFirmware::marlin, d);
  REQUIRE(tau);
  CHECK(*tau == Approx(design::design_marlin_advance_tau(0.0093).tau_s));
  CHECK(design::marlin_smoothing_peak_slope_per_s(*tau) * d.window_box_s <= 1.0);
  CHECK(design::marlin_smoothing_peak_slope_per_s(*tau - 1e-4) * d.window_box_s > 1.0);
}
