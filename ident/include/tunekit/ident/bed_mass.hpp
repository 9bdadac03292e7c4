#pragma once
// The bed axis of a bed slinger under load. The bed, its carriage and the belt's share move as
// one effective mass m0 on the axis' stiffness k (belt and motor), and a print of mass m rides
// on it, so the axis' first mode runs at
//     f(m) = (1 / 2 pi) sqrt(k / (m0 + m))        (Hz; m0 and m in kg, k in N/m = 1000 x N/mm)
// Sweeps of the axis with known added masses (each fitted by identify_modes, resonance.hpp)
// give (m_i, f_i +- s_i); fit_bed_mass() fits m0 and k by weighted least squares on the
// frequencies (the standard errors of the sweeps' fits as the weights), with their covariance
// from the sweeps' errors (absolute: two sweeps determine both parameters exactly, a third
// checks the model; with more sweeps than parameters the covariance is widened by the reduced
// chi-square when that is above 1). The damping ratio's trend with the mass is fitted as a
// straight line, and a viscous damper c (N s/m) would make zeta = c / (2 sqrt(k (m0 + m))).

#include <array>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::ident {

/// One sweep of the bed axis with a known mass added to the bed: its first mode's frequency and
/// damping ratio with their standard errors (Hz, 1), and where they came from.
struct BedMassPoint {
  double added_mass_kg = 0;
  double freq_hz = fitting::kNaN;
  double freq_stderr_hz = fitting::kNaN;
  double zeta = fitting::kNaN;
  double zeta_stderr = fitting::kNaN;
  std::string source;
};

/// The frequency the model predicts at an added mass, with its standard error and 95 % interval.
struct BedFrequencyPrediction {
  double added_mass_kg = 0;
  double freq_hz = fitting::kNaN;
  double stderr_hz = fitting::kNaN;
  double ci95_lo_hz = fitting::kNaN, ci95_hi_hz = fitting::kNaN;
};

/// f(m) = sqrt(k / (m0 + m)) / (2 pi) with the covariance of (m0, k).
struct BedMassModel {
  double moving_mass_kg = fitting::kNaN;      ///< m0, the axis' effective moving mass (kg)
  double stiffness_N_per_mm = fitting::kNaN;  ///< k, the axis' stiffness (N/mm)
  std::array<double, 4> covariance{};         ///< row-major over (m0 kg, k N/mm)
  /// The frequency (Hz) with `added_kg` on the bed.
  double freq_hz(double added_kg) const;
  /// The added mass (kg) at which the axis runs at `freq_hz`.
  double added_mass_at(double freq_hz) const;
  /// f(m) with its standard error by the delta method over the covariance.
  BedFrequencyPrediction predict(double added_kg) const;
  /// The correlation of m0 and k (-1 .. 1).
  double correlation() const;
};

/// The damping ratio's trend: zeta = zeta0 + slope m (weighted straight line), and the viscous
/// damping c = 2 zeta sqrt(k (m0 + m)) (N s/m) each sweep implies, their weighted mean.
struct BedDampingTrend {
  double zeta0 = fitting::kNaN;
  double slope_per_kg = fitting::kNaN;
  double slope_stderr_per_kg = fitting::kNaN;
  double slope_ci95_lo = fitting::kNaN, slope_ci95_hi = fitting::kNaN;
  std::vector<double> damping_N_s_per_m;  ///< per sweep, in the order of the points
  double mean_damping_N_s_per_m = fitting::kNaN;
};

struct BedMassFit {
  /// Parameters moving_mass_kg and stiffness_N_per_mm (with standard errors and normal 95 %
  /// intervals) and their covariance; diagnostics of the weighted fit.
  fitting::FitResult fit;
  BedMassModel model;
  double chi_square = 0;  ///< sum of the squared weighted residuals
  int dof = 0;            ///< sweeps - 2
  BedDampingTrend damping;
  std::vector<BedMassPoint> points;
  std::vector<std::string> warnings;
};

/// Fits f(m) to two or more sweeps at two or more different masses. InputError for fewer, for a
/// frequency or standard error that is not positive, or for frequencies that do not fall as the
/// mass grows; FitError when the fit fails.
BedMassFit fit_bed_mass(const std::vector<BedMassPoint>& points);

/// A sweep the fit did not use, against the model's prediction at its mass.
struct BedHeldOutCheck {
  BedMassPoint point;
  BedFrequencyPrediction predicted;
  double error_hz = fitting::kNaN;  ///< measured - predicted
  double relative_error = fitting::kNaN;
  double z = fitting::kNaN;  ///< error / sqrt(prediction variance + the sweep's variance)
};
BedHeldOutCheck check_held_out(const BedMassModel& model, const BedMassPoint& point);

}  // namespace tunekit::ident
