#include "tunekit/design/marlin_smoothing.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::design {
namespace {

void check_marlin_filter(const MarlinSmoothingFilter& f) {
  if (f.order < 1 || f.order > 20) throw InputError(fmt::format("smoothing order must be 1 to 20, not {}", f.order));
  if (!std::isfinite(f.update_hz) || f.update_hz <= 0)
    throw InputError(fmt::format("smoothing update rate must be > 0 Hz, not {}", f.update_hz));
}

}  // namespace

double marlin_smoothing_alpha(double tau_s, const MarlinSmoothingFilter& filter) {
  check_marlin_filter(filter);
  if (!std::isfinite(tau_s) || tau_s <= 0) throw InputError(fmt::format("ADVANCE_TAU must be > 0 s, not {}", tau_s));
  return -std::expm1(-static_cast<double>(filter.order) / (tau_s * filter.update_hz));
}

double marlin_smoothing_peak_slope_per_s(double tau_s, const MarlinSmoothingFilter& filter) {
  const double alpha = marlin_smoothing_alpha(tau_s, filter);
  const double p = 1.0 - alpha;
  const int n_stages = filter.order;
  // h[n] = alpha^N C(n+N-1, N-1) p^n rises while p (n+N-1)/n > 1, then falls: walk to the top.
  double h = std::pow(alpha, n_stages);
  for (long n = 1;; ++n) {
    const double next = h * p * static_cast<double>(n + n_stages - 1) / static_cast<double>(n);
    if (!(next > h)) break;
    h = next;
  }
  return h * filter.update_hz;
}

double marlin_smoothing_continuous_peak_factor(int order) {
  if (order < 1) throw InputError(fmt::format("smoothing order must be >= 1, not {}", order));
  if (order == 1) return 1.0;
  const double m = order - 1.0;
  return order * std::exp(m * std::log(m) - m - std::lgamma(m + 1.0));
}

MarlinTauDesign design_marlin_advance_tau(double box_window_s, const MarlinSmoothingFilter& filter,
                                          double resolution_s) {
  check_marlin_filter(filter);
  if (!std::isfinite(box_window_s) || box_window_s <= 0)
    throw InputError(
        fmt::format("the smoothing design needs a positive box window (K r a / a_max), not {} s", box_window_s));
  if (!std::isfinite(resolution_s) || resolution_s <= 0)
    throw InputError(fmt::format("tau resolution must be > 0 s, not {}", resolution_s));
  const double slope_max = 1.0 / box_window_s;
  const auto meets = [&](long steps) {
    return marlin_smoothing_peak_slope_per_s(static_cast<double>(steps) * resolution_s, filter) <= slope_max;
  };
  const long cap = static_cast<long>(std::ceil(kMarlinTauMax_s / resolution_s - 1e-9));
  // Start at the continuous estimate c(N) * box and walk on the grid to the shortest tau that
  // meets the limit (the peak slope falls as tau grows).
  long s = std::clamp(
      static_cast<long>(std::ceil(marlin_smoothing_continuous_peak_factor(filter.order) * box_window_s / resolution_s)),
      1L, cap + 1);
  while (s <= cap && !meets(s)) ++s;
  while (s > 1 && meets(s - 1)) --s;
  if (s > cap || !meets(s))
    throw InputError(fmt::format(
        "Marlin's smooth linear advance would need ADVANCE_TAU above {} s (M900 U accepts 0 to {} s) to keep the extra "
        "extruder acceleration within the limit: lower K, the print acceleration, or raise the extruder's limit",
        kMarlinTauMax_s, kMarlinTauMax_s));
  MarlinTauDesign d;
  d.required_tau_s = static_cast<double>(s) * resolution_s;
  d.floor_tau_s = std::ceil(filter.order / filter.update_hz / resolution_s - 1e-9) * resolution_s;
  d.tau_s = std::max(d.required_tau_s, d.floor_tau_s);
  d.extra_accel_per_box_mm_s2 = marlin_smoothing_peak_slope_per_s(d.tau_s, filter) * box_window_s;
  if (d.tau_s > d.required_tau_s)
    d.notes.push_back(
        fmt::format("ADVANCE_TAU raised from {:.4g} s to {:.4g} s: below one update period per stage "
                    "({} stages at {:g} Hz) the filter smooths nothing",
                    d.required_tau_s, d.tau_s, filter.order, filter.update_hz));
  d.notes.push_back(
      fmt::format("ADVANCE_TAU {:.4g} s is also how far Marlin looks ahead into the planner: the "
                  "buffered moves must cover it",
                  d.tau_s));
  return d;
}

}  // namespace tunekit::design
