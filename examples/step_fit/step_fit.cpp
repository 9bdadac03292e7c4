// Fit a step log with a first-order-plus-dead-time (FOPDT) model.
//
// A liquefier's feed force answers a step of the feed rate like a first-order system with a dead
// time (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente, 2019, eq. 4.5-4.8):
//
//   y(t) = y0                                              before t_step + theta
//   y(t) = y0 + K du (1 - exp(-(t - t_step - theta) / tau))  afterwards
//
// This program writes such a log itself (a feed step of 1.5 mm/s at t = 2 s, a force sensor
// with 0.15 N of noise, 100 samples per second) and fits K, tau and theta with their 95 %
// intervals. To fit your own log, fill StepRecord from your file instead.
//
//   step_fit

#include <cstdio>
#include <exception>
#include <random>

#include "tunekit/fitting/first_order.hpp"

int main() {
  namespace fit = tunekit::fitting;

  // 1. The log: time (s) and force (N), and when and by how much the feed rate changed.
  //    Samples before the step give y0 and let the fit see where the response starts.
  fit::StepRecord rec;
  rec.t_step = 2.0;                                               // s
  rec.du = 1.5;                                                   // mm/s: the feed rate went from 1.0 to 2.5 mm/s
  rec.output_unit = "N";                                          // unit of y and y0
  rec.gain_unit = "N/(mm/s)";                                     // unit of K
  const double K = 12.0, tau_s = 0.6, theta_s = 0.15, y0 = 15.0;  // the "unknown" truth
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.15);
  for (int i = 0; i <= 1000; ++i) {
    const double t = 0.01 * i;
    rec.t.push_back(t);
    rec.y.push_back(fit::step_response(t, rec.t_step, rec.du, K, tau_s, theta_s, y0) + noise(rng));
  }

  // 2. The fit. fit_step finds its own start values (the log-incomplete-response method) and
  //    throws when the record cannot show tau or theta; every tunekit error derives from
  //    std::runtime_error and says what is wrong.
  fit::FitResult result;
  try {
    result = fit::fit_step(rec, fit::StepModel::fopdt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "step_fit: %s\n", e.what());
    return 1;
  }

  // 3. The result: each parameter with its unit, standard error and 95 % interval, and how
  //    well the model explains the data (r2; whiteness_p small means the residuals are
  //    correlated, i.e. the model misses some dynamics).
  std::printf("model %s, %d samples\n", result.model.c_str(), result.diagnostics.num_observations);
  for (const fit::Param& p : result.params)
    std::printf("%-8s %9.4f %-9s (95 %% interval %.4f to %.4f)\n", p.name.c_str(), p.value, p.unit.c_str(), p.ci95_lo,
                p.ci95_hi);
  std::printf("r2 %.5f, rms %.4f N, residual whiteness p %.3f\n", result.diagnostics.r2, result.diagnostics.rms,
              result.diagnostics.whiteness_p);
  return 0;
}
