#include "tunekit/protocols/chirp_plan.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::protocols {

std::size_t ChirpPlan::welch_segment_samples(double sample_rate_hz) const {
  if (!(sample_rate_hz > 0) || !std::isfinite(sample_rate_hz))
    throw InputError(fmt::format("sample rate must be positive, not {:g} Hz", sample_rate_hz));
  const double want = welch_segment_s * sample_rate_hz;
  std::size_t n = 16;
  while (static_cast<double>(n) < want && n < (std::size_t{1} << 20)) n *= 2;
  return n;
}

ChirpPlan plan_liquefier_chirp(double tau_s, double staircase_step_s) {
  if (!(tau_s > 0) || !std::isfinite(tau_s))
    throw InputError(fmt::format("the expected liquefier time constant must be positive, not {:g} s", tau_s));
  if (!(staircase_step_s > 0) || !std::isfinite(staircase_step_s))
    throw InputError(fmt::format("the chirp's staircase step must be positive, not {:g} s", staircase_step_s));
  ChirpPlan p;
  p.expected_tau_s = tau_s;
  p.corner_hz = 1.0 / (2 * std::numbers::pi * tau_s);
  const double reach_hz = 1.0 / (10 * staircase_step_s);  // 10 feed levels per period
  // A decade below the corner, but an octave below the staircase's reach at most: an extruder
  // whose staircase is slow (a low extrude-only acceleration) still gets a chirp it can run.
  p.freq_min_hz = std::min(p.corner_hz / 10, reach_hz / 2);
  p.freq_max_hz = std::max(std::min(5 * p.corner_hz, reach_hz), 2 * p.freq_min_hz);
  p.duration_s = std::max(20.0, 20.0 / p.corner_hz);
  p.settle_s = std::max(2.0, 10 * tau_s);
  // Nine time constants of the settle are enough for the start-up transient to fade below
  // 1e-4 of the step it answers; one more tau of steady feed is kept in the record.
  p.analysis_start_s = p.settle_s - tau_s;
  p.welch_segment_s = 3.0 / p.corner_hz;
  p.analysis_fmax_hz = p.freq_max_hz;  // above the chirp's end nothing is excited
  return p;
}

}  // namespace tunekit::protocols
