#pragma once
// What a first-order liquefier model with dead time, G(s) = exp(-theta s) / (1 + tau s), predicts
// for a printed ring whose flow is modulated at one frequency (the ring test: the extrusion
// varies as 1 + A sin(N phi) along the circle, f = N v / (2 pi R)), and the dead time the ring's
// measured phase implies with tau known from another test (Holtrup, Tuning liquefier dynamics,
// University of Twente, 2019, ch. 4.3: the frequency response of the same model).

#include <limits>

namespace tunekit::ident {

/// A model identified elsewhere (the printed lines' steps): tau and theta in s with their standard
/// errors (NaN when not known; a NaN theta is taken as 0).
struct RingModel {
  double tau_s = std::numeric_limits<double>::quiet_NaN(), theta_s = std::numeric_limits<double>::quiet_NaN();
  double tau_stderr_s = std::numeric_limits<double>::quiet_NaN(),
         theta_stderr_s = std::numeric_limits<double>::quiet_NaN();
};

/// The ring as photographed: its modulation frequency (Hz) and the measured phase of the width
/// against the commanded flow (deg, with its standard error).
struct RingMeasurement {
  double freq_hz = std::numeric_limits<double>::quiet_NaN();
  double phase_deg = std::numeric_limits<double>::quiet_NaN();
  double phase_stderr_deg = std::numeric_limits<double>::quiet_NaN();
};

/// The model's prediction at the ring's frequency: gain (relative to the steady gain, as the
/// ring's measured gain is) and phase (deg), and the dead time (s) the ring's measured phase
/// implies with the model's tau. Interval bounds (95 %) are NaN when a standard error is not known.
struct RingPrediction {
  double model_gain = std::numeric_limits<double>::quiet_NaN();
  double model_phase_deg = std::numeric_limits<double>::quiet_NaN();
  double model_phase_ci95_lo_deg = std::numeric_limits<double>::quiet_NaN(),
         model_phase_ci95_hi_deg = std::numeric_limits<double>::quiet_NaN();
  double theta_from_phase_s = std::numeric_limits<double>::quiet_NaN();
  double theta_from_phase_ci95_lo_s = std::numeric_limits<double>::quiet_NaN(),
         theta_from_phase_ci95_hi_s = std::numeric_limits<double>::quiet_NaN();
};

/// The prediction for `ring` from `model` (tau must be finite).
RingPrediction predict_ring(const RingModel& model, const RingMeasurement& ring);

}  // namespace tunekit::ident
