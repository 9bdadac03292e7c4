#include "tunekit/ident/ring_prediction.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <tuple>
#include <utility>

#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

constexpr double kDegPerRad = 180 / std::numbers::pi;

// value +- 1.96 stderr as an interval (NaN bounds when the standard error is not known).
std::pair<double, double> ring_ci95(double value, double stderr_) {
  if (!std::isfinite(value) || !std::isfinite(stderr_)) return {std::nan(""), std::nan("")};
  return {value - fitting::kZ95 * stderr_, value + fitting::kZ95 * stderr_};
}

}  // namespace

RingPrediction predict_ring(const RingModel& model, const RingMeasurement& ring) {
  const double tau = model.tau_s;
  const double theta = std::isfinite(model.theta_s) ? model.theta_s : 0.0;
  const double w = 2 * std::numbers::pi * ring.freq_hz;
  // The ring's gain is relative to the steady width (vision::RingResult), the model's likewise:
  // its response at f over its steady gain K.
  const std::complex<double> G = std::exp(std::complex<double>(0, -w * theta)) / std::complex<double>(1, w * tau);
  RingPrediction p;
  // d(-atan(w tau))/d tau = -w / (1 + (w tau)^2): tau's error as phase (rad).
  const double tau_phase_se = w * model.tau_stderr_s / (1 + w * w * tau * tau);
  p.model_gain = std::abs(G);
  p.model_phase_deg = std::arg(G) * kDegPerRad;
  // tau and theta from one fit are negatively correlated; adding their variances overstates the
  // phase's, so this interval is on the wide side.
  std::tie(p.model_phase_ci95_lo_deg, p.model_phase_ci95_hi_deg) =
      ring_ci95(std::arg(G) * kDegPerRad, std::hypot(tau_phase_se, w * model.theta_stderr_s) * kDegPerRad);
  // The dead time the ring's phase implies with the lines' tau: phase = -atan(w tau) - w theta.
  // It does not depend on where the lines lie on their paths (the weak point of a photo whose
  // placement on the bed is not known), only on the ring's start direction (+X). Its error: the
  // ring's phase and the lines' tau, independent measurements.
  const double lag = -ring.phase_deg / kDegPerRad - std::atan(w * tau);
  p.theta_from_phase_s = lag / w;
  std::tie(p.theta_from_phase_ci95_lo_s, p.theta_from_phase_ci95_hi_s) =
      ring_ci95(lag / w, std::hypot(ring.phase_stderr_deg / kDegPerRad, tau_phase_se) / w);
  return p;
}

}  // namespace tunekit::ident
