#pragma once
// The resonances of an axis from its accelerometer record and the motion that was commanded:
// an output-error fit in the time domain.
//
// A spectrum (Welch's averaged periodogram of a sweep) describes a resonance only approximately:
// the sweep passes the peak at a finite rate, the window smears it, and the excitation's shape
// is assumed. When the commanded motion is known piece by piece (commanded_motion.hpp), the
// record itself can be modelled: the accelerometer reads
//     y(t) = a(t) + sum_k g_k z_k''(t) + offset,
// a(t) the commanded acceleration, z_k the deflection of mode k driven through its base
// (base_excited_mode.hpp, exact over each piece), g_k the share of the motion the mode carries
// (1 for a single mode that carries it all), offset the sensor's bias. Each mode's deflection at
// the record's first sample is estimated too (what the motion before the record left ringing).
// The parameters minimise the squared difference with the record (Ljung, System Identification:
// Theory for the User, 1999, section 7.2, the output-error model). Their intervals are the
// least-squares ones, inflated by the residuals' autocorrelation (fitting::residual_variance_factor,
// Bartlett 1935) where the model does not describe the record to its noise. Starting values come
// from the spectrum's modal fit.

#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/modal_fit.hpp"
#include "tunekit/ident/commanded_motion.hpp"
#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

struct AxisResponseOptions {
  double confidence = 0.95;
  double max_zeta = 0.5;  ///< upper bound of each damping ratio
};

struct AxisResponseFit {
  fitting::FitResult fit;                    ///< freq_hz_k, zeta_k, gain_k, z0_mm_k, v0_mm_s_k, offset_mm_s2
  std::vector<fitting::ModeEstimate> modes;  ///< sorted by frequency, intervals inflated
  double variance_inflation = 1;
  std::size_t samples = 0;
  std::size_t pieces = 0;  ///< pieces of commanded motion within the record
};

/// Fits the modes of `record`'s channel for its axis ("accel_x" for 'x') against `motion` (that
/// axis' commanded motion on the record's clock), from `starts`. InputError when the record has
/// no such channel or the motion does not overlap the record; FitError when the fit fails.
AxisResponseFit fit_axis_response(const AccelRecord& record, const std::vector<AccelPiece>& motion,
                                  const std::vector<fitting::ModeStart>& starts,
                                  const AxisResponseOptions& options = {});

/// How far the fit against the motion may lie from the spectrum's fit, in half-widths of the
/// spectrum's 95 % interval, before it is not believed: the spectrum's interval carries its own
/// model error, so two estimates of one mode lie within it; three half-widths apart, one of them
/// is wrong (a motion on another clock than the samples, a record of something else).
inline constexpr double kMotionFitAgreementHalfWidths = 3.0;

/// Replaces the spectrum's modes in `m` by the fit of `record` against `motion` (method
/// "output_error"), started from them. The spectrum's modes stay, with a warning that says why,
/// when that fit fails or when a mode's frequency or damping ratio lies more than
/// kMotionFitAgreementHalfWidths of the spectrum's interval away from the spectrum's estimate.
void refine_modes_with_motion(AxisModes& m, const AccelRecord& record, const std::vector<AccelPiece>& motion);

}  // namespace tunekit::ident
