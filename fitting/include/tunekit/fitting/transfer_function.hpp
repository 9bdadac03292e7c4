#pragma once
// Low-order continuous transfer functions (up to 3 poles and 2 zeros, optional dead time):
// frequency response, exact zero-order-hold simulation with fractional delays, and fits to
// frequency-response points (complex residuals weighted by each point's uncertainty) or to
// an arbitrary input/output record by output error.
//
// Parameterization (the names used in FitResult and JSON):
//   G(s) = K * N(s) / D(s) * exp(-theta_s s)
//   D(s): poles 1: (tau_s s + 1); 2: (s^2/wn^2 + 2 zeta s/wn + 1), wn = 2 pi fn_hz; 3: both.
//   N(s): zeros 0: 1; 1: (tz_s s + 1); 2: (b2_s2 s^2 + b1_s s + 1).
// fn_hz/zeta also describe two real poles (zeta > 1). tz_s < 0 is a right-half-plane zero.

#include <complex>
#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

struct TransferFunction {
  std::vector<double> num;  ///< coefficients in descending powers of s
  std::vector<double> den;  ///< descending powers of s; den.front() != 0; num.size() <= den.size()
  double delay_s = 0;       ///< dead time (s), >= 0

  /// G(j 2 pi f).
  std::complex<double> response(double freq_hz) const;
  /// Steady-state gain G(0).
  double dc_gain() const;
  /// Output at the sample times k dt for an input held constant between samples (zero-order
  /// hold), starting at rest with u = 0 before the record. Exact for any delay, including
  /// fractions of a sample. Throws InputError for dt <= 0 or an improper / empty model.
  std::vector<double> simulate_zoh(std::span<const double> u, double dt) const;
  /// Output at the sample times k dt for an input that is linear between samples (first-order
  /// or triangle hold: Franklin, Powell and Workman, "Digital Control of Dynamic Systems",
  /// 1998, section 6.3), starting at rest with u = 0 before the record: the right model of a
  /// sampled continuous input (a chirp, a feed that accelerates), where the zero-order hold
  /// would add half a sample of delay. Exact for any delay. Throws as simulate_zoh.
  std::vector<double> simulate_foh(std::span<const double> u, double dt) const;
};

struct TfStructure {
  int poles = 2;
  int zeros = 0;
  bool delay = false;
};

/// Parses "P,Z" (e.g. "2,0"), 1 <= P <= 3, 0 <= Z <= min(P, 2); InputError otherwise.
TfStructure parse_tf_structure(const std::string& text);
/// "tf(P,Z)" or "tf(P,Z)+delay".
std::string tf_model_name(const TfStructure& s);
/// Parameter names in order (K, fn_hz, zeta, tau_s, tz_s | b1_s, b2_s2, theta_s).
std::vector<std::string> tf_param_names(const TfStructure& s);
/// Builds the transfer function from parameter values in tf_param_names order.
TransferFunction tf_from_params(const TfStructure& s, const double* p);
/// As above from a fit (its parameters by name).
TransferFunction tf_from_fit(const TfStructure& s, const FitResult& f);

/// Fits G to frequency-response points h (output/input) at freq_hz, each with a standard
/// uncertainty sigma (of the complex value; weights 1/sigma on real and imaginary parts).
/// Multi-start over a grid of pole positions inside the band, then a final fit with intervals.
FitResult fit_tf_frf(std::span<const double> freq_hz, std::span<const std::complex<double>> h,
                     std::span<const double> sigma, const TfStructure& s, const std::string& gain_unit = "1");

/// How the input behaves between its samples (the inter-sample behaviour of Ljung, System
/// Identification: Theory for the User, 1999, ch. 13; MATLAB's iddata InterSample property).
enum class InterSample {
  /// From the record: `hold_centred` when the input repeats its value over most samples (a
  /// staircase), else `band_limited` (a sampled continuous input such as a chirp).
  automatic,
  /// Held from each sample's time stamp to the next (zero-order hold): a command a controller
  /// applied at the instant it logged it.
  hold,
  /// Each sample stands for the interval centred on its time stamp (a mean over it, or a value
  /// that changed at an unknown moment of the interval before): linear between the samples, so
  /// each change is centred half a sample before the sample that first shows it. tunekit's own
  /// recordings (the feed column of a load-cell record) are of this kind.
  hold_centred,
  /// A band-limited continuous signal: linear between the samples, with the interpolation's
  /// attenuation undone to fourth order in f dt.
  band_limited,
};
InterSample parse_inter_sample(const std::string& name);  ///< auto, hold, centred, bandlimited
std::string to_string(InterSample s);

/// Output-error fit of G (plus an output offset y0) to a uniformly sampled record: the model
/// output is the simulation of (u - u[0]) plus y0, the input between samples as `inter_sample`
/// says. `start` gives the TF parameters to start from (e.g. from fit_tf_frf); y0 starts at y[0].
FitResult fit_tf_output_error(std::span<const double> u, std::span<const double> y, double dt, const TfStructure& s,
                              const FitResult& start, const std::string& gain_unit = "1",
                              const LsqOptions& options = {}, InterSample inter_sample = InterSample::automatic);

/// The uncertainty of an H1 estimate from its coherence and the number of averaged segments
/// (Bendat & Piersol): sigma = |H| sqrt((1 - g2) / (2 n g2)); g2 is clamped to [1e-6, 0.9999].
double h1_sigma(std::complex<double> h, double coherence, std::size_t segments);

}  // namespace tunekit::fitting
