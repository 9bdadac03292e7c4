#pragma once
// Modal identification: a sum of second-order modes fitted to a power spectral density (PSD)
// or to a frequency response (FRF), giving each mode's natural frequency and damping ratio
// with 95 % intervals.
//
// Model (proportionally damped structure seen from one input to one output):
//   H(f) = d + sum_k g_k f_k^2 / (f_k^2 - f^2 + 2 j z_k f_k f)
// with natural frequency f_k (Hz), damping ratio z_k, real modal gain g_k and a real direct
// term d (the rigid-body / residual part). For a PSD the data are
//   P(f) = E(f) |H(f)|^2 + n0,     E(f) = (f / f_ref)^p,
// where E is the known shape of the excitation spectrum (a Klipper-style sweep with
// acceleration amplitude proportional to f gives p = 2 on the raw PSD) and n0 the noise floor.
// A Welch estimate is the true spectrum smoothed by the window's spectral kernel
// |W(f)|^2 (leakage); the model is convolved with that kernel so that the damping is not
// overestimated when the half-power bandwidth is only a few bins wide.
//
// The PSD fit minimizes the squared log ratio ln(model / data) (Welch estimates have a roughly
// constant relative error), with the least-squares core of least_squares.hpp. Adjacent Welch
// bins are correlated, so the parameter covariance is inflated by the variance inflation factor
// 1 + 2 sum_k (1 - k/(L+1)) rho_k of the residuals (Bartlett-weighted autocorrelations up to
// lag L) before intervals are formed.

#include <complex>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::fitting {

/// Spectral smoothing of an estimator: model value at f is sum_j weight_j S(f + offset_j).
/// Weights sum to 1. Empty: no smoothing.
struct SpectralKernel {
  std::vector<double> offsets_hz;
  std::vector<double> weights;
};

struct ModeStart {
  double freq_hz = 0;
  double zeta = 0.05;
  double gain = 1;  ///< start value of g_k (sign matters for close modes)
};

struct ModeEstimate {
  double freq_hz = kNaN;
  double zeta = kNaN;
  double gain = kNaN;
  double freq_stderr_hz = kNaN;
  double zeta_stderr = kNaN;
  double freq_ci95_lo = kNaN, freq_ci95_hi = kNaN;
  double zeta_ci95_lo = kNaN, zeta_ci95_hi = kNaN;
};

struct ModalFitOptions {
  double excitation_exponent = 2.0;  ///< p in E(f) = (f/f_ref)^p
  bool fit_direct_term = true;       ///< estimate d (else d = 0)
  bool fit_noise_floor = true;       ///< estimate n0 (PSD only; else n0 = 0)
  int correlation_lags = 8;          ///< L for the variance inflation factor; 0: no inflation
  double confidence = 0.95;
  double max_zeta = 0.5;
};

struct ModalFit {
  FitResult fit;                    ///< parameters freq_hz_k, zeta_k, gain_k (k = 1..), direct, floor
  std::vector<ModeEstimate> modes;  ///< sorted by frequency
  double direct_term = 0;
  double noise_floor = 0;         ///< in the data's units
  double variance_inflation = 1;  ///< applied to the covariance
  std::vector<double> model;      ///< fitted PSD (or |FRF|) at the data frequencies
  std::vector<std::string> warnings;
};

/// Widens the fit's intervals for residuals correlated across neighbouring bins: the standard
/// errors grow by sqrt(vif) and the intervals take the t quantile at `confidence` with the degrees
/// of freedom divided by vif (the variance inflation factor, >= 1). Fixed parameters and those
/// without a finite standard error are left as they are.
void inflate_uncertainty(FitResult& fit, double vif, double confidence);

/// The modes of fitted parameters laid out in blocks of `stride` per mode, each block starting
/// with frequency (Hz), damping ratio and gain (freq_hz_k, zeta_k, gain_k); sorted by frequency,
/// the damping ratio's lower bound clipped at 0.
std::vector<ModeEstimate> modes_from_params(const std::vector<Param>& params, std::size_t modes, std::size_t stride);

/// Fits the PSD model to (freq_hz, psd) with one mode per start value. Bins with psd <= 0 are
/// ignored. Throws InputError for inconsistent data or too few bins, FitError when the fit
/// fails or the modes are not identifiable.
ModalFit fit_modal_psd(const std::vector<double>& freq_hz, const std::vector<double>& psd,
                       const std::vector<ModeStart>& starts, const SpectralKernel& kernel,
                       const ModalFitOptions& options = {});

/// Fits H(f) to a measured frequency response (e.g. the H1 estimate) on bins with
/// coherence >= min_coherence, minimizing the relative complex error |model - h| / |h|.
ModalFit fit_modal_frf(const std::vector<double>& freq_hz, const std::vector<std::complex<double>>& h,
                       const std::vector<double>& coherence, double min_coherence, const std::vector<ModeStart>& starts,
                       const SpectralKernel& kernel, const ModalFitOptions& options = {});

}  // namespace tunekit::fitting
