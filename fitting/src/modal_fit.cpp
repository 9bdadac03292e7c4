#include "tunekit/fitting/modal_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::fitting {
namespace {

using cd = std::complex<double>;

// H(f) and its derivatives with respect to the parameters [f_1, z_1, g_1, ..., d].
// dh has 3 * modes + 1 entries.
void eval_h(const double* p, int modes, double f, cd& h, cd* dh) {
  h = cd(p[3 * modes], 0);
  for (int k = 0; k < modes; ++k) {
    const double fk = p[3 * k], zk = p[3 * k + 1], gk = p[3 * k + 2];
    const cd D(fk * fk - f * f, 2 * zk * fk * f);
    const cd Hk = fk * fk / D;
    h += gk * Hk;
    if (dh != nullptr) {
      const cd D2 = D * D;
      dh[3 * k] = gk * (2 * fk * D - fk * fk * cd(2 * fk, 2 * zk * f)) / D2;
      dh[3 * k + 1] = gk * (-fk * fk * cd(0, 2 * fk * f)) / D2;
      dh[3 * k + 2] = Hk;
    }
  }
  if (dh != nullptr) dh[3 * modes] = cd(1, 0);
}

SpectralKernel identity_kernel() { return {{0.0}, {1.0}}; }

// Variance inflation factor from Bartlett-weighted residual autocorrelations.
double variance_inflation(const std::vector<double>& r, int lags) {
  if (lags <= 0 || r.size() < 8) return 1.0;
  const double n = static_cast<double>(r.size());
  const double mean = std::accumulate(r.begin(), r.end(), 0.0) / n;
  double c0 = 0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  if (!(c0 > 0)) return 1.0;
  double vif = 1.0;
  for (int k = 1; k <= lags && static_cast<std::size_t>(k) < r.size(); ++k) {
    double ck = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < r.size(); ++i) ck += (r[i] - mean) * (r[i - k] - mean);
    vif += 2.0 * (1.0 - k / (lags + 1.0)) * (ck / c0);
  }
  return std::clamp(vif, 1.0, 50.0);
}

std::vector<ParamSpec> mode_params(const std::vector<ModeStart>& starts, double fmin, double fmax, double max_zeta) {
  std::vector<ParamSpec> ps;
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const auto idx = std::to_string(k + 1);
    const double f0 = starts[k].freq_hz;
    ps.push_back({"freq_hz_" + idx, "Hz", f0, std::max(fmin, 0.5 * f0), std::min(fmax, 1.5 * f0)});
    ps.push_back({"zeta_" + idx, "1", std::clamp(starts[k].zeta, 2e-4, max_zeta), 1e-4, max_zeta});
    ps.push_back({"gain_" + idx, "1", starts[k].gain});
  }
  return ps;
}

// Turns the fit's parameters into mode estimates with inflated uncertainty.
void finish(ModalFit& out, int modes, double vif, double confidence) {
  out.variance_inflation = vif;
  inflate_uncertainty(out.fit, vif, confidence);
  out.modes = modes_from_params(out.fit.params, static_cast<std::size_t>(modes), 3);
}

void check_starts(const std::vector<ModeStart>& starts) {
  if (starts.empty()) throw InputError("modal fit: no modes to fit (no resonance peak was found)");
  for (const auto& s : starts)
    if (!(s.freq_hz > 0) || !std::isfinite(s.freq_hz)) throw InputError("modal fit: a start frequency is not positive");
}

// Tight tolerances: mode parameters are few and the spectra are smooth, so convergence is cheap.
LsqOptions modal_lsq_options(double confidence) {
  LsqOptions lo;
  lo.max_iterations = 300;
  lo.function_tolerance = 1e-12;
  lo.gradient_tolerance = 1e-12;
  lo.parameter_tolerance = 1e-10;
  lo.confidence = confidence;
  return lo;
}

// The index of the bin whose frequency lies nearest `freq_hz` (the first of equally near ones).
std::size_t nearest_bin(const std::vector<double>& f, double freq_hz) {
  std::size_t best = 0;
  for (std::size_t b = 0; b < f.size(); ++b)
    if (std::abs(f[b] - freq_hz) < std::abs(f[best] - freq_hz)) best = b;
  return best;
}

// The kernel's abscissae and excitation-weighted weights per bin: entry b * nk + j is the j-th
// kernel point of bin b.
struct KernelGrid {
  std::size_t nk = 0;
  std::vector<double> fj, wj;
};

KernelGrid kernel_grid(const std::vector<double>& f, const SpectralKernel& kernel, double fref, double exponent) {
  KernelGrid g;
  g.nk = kernel.offsets_hz.size();
  g.fj.resize(f.size() * g.nk);
  g.wj.resize(f.size() * g.nk);
  for (std::size_t b = 0; b < f.size(); ++b)
    for (std::size_t j = 0; j < g.nk; ++j) {
      const double x = f[b] + kernel.offsets_hz[j];
      g.fj[b * g.nk + j] = x;
      g.wj[b * g.nk + j] = x > 0 ? kernel.weights[j] * std::pow(x / fref, exponent) : 0.0;
    }
  return g;
}

// The fitted parameters' values.
std::vector<double> param_values(const FitResult& fit) {
  std::vector<double> p;
  for (const auto& q : fit.params) p.push_back(q.value);
  return p;
}

// The PSD bins a fit uses (positive, finite, at positive frequency), scaled to their maximum.
struct PsdBins {
  std::vector<double> f, y, logy;  ///< frequency (Hz), y = psd / pmax, log(y)
  double pmax = 0;
};

PsdBins usable_psd_bins(const std::vector<double>& freq, const std::vector<double>& psd) {
  PsdBins bins;
  for (std::size_t b = 0; b < freq.size(); ++b)
    if (psd[b] > 0 && std::isfinite(psd[b]) && freq[b] > 0) {
      bins.f.push_back(freq[b]);
      bins.y.push_back(psd[b]);
      bins.pmax = std::max(bins.pmax, psd[b]);
    }
  for (double& v : bins.y) v /= bins.pmax;  // fit in relative units; gains and floor are scaled back
  bins.logy.resize(bins.y.size());
  for (std::size_t b = 0; b < bins.y.size(); ++b) bins.logy[b] = std::log(bins.y[b]);
  return bins;
}

// Residuals log(model) - log(y) of the kernel-smoothed PSD model and their Jacobian; the
// parameters are those of mode_params, then the direct term and the floor.
ResidualJacobianFunction psd_residuals(const PsdBins& bins, const KernelGrid& grid, int modes) {
  const int np = 3 * modes + 2;
  return [&bins, &grid, modes, np](const double* p, double* r, double* jac) -> bool {
    const std::vector<double>& f = bins.f;
    const std::size_t nk = grid.nk;
    std::vector<cd> dh(static_cast<std::size_t>(3 * modes + 1));
    std::vector<double> dm(static_cast<std::size_t>(np));
    for (std::size_t b = 0; b < f.size(); ++b) {
      double m = p[np - 1];
      std::fill(dm.begin(), dm.end(), 0.0);
      for (std::size_t j = 0; j < nk; ++j) {
        const double w = grid.wj[b * nk + j];
        if (w == 0) continue;
        cd h;
        eval_h(p, modes, grid.fj[b * nk + j], h, jac != nullptr ? dh.data() : nullptr);
        m += w * std::norm(h);
        if (jac != nullptr)
          for (int q = 0; q < 3 * modes + 1; ++q)
            dm[static_cast<std::size_t>(q)] += w * 2 * std::real(std::conj(h) * dh[static_cast<std::size_t>(q)]);
      }
      if (!(m > 0) || !std::isfinite(m)) return false;
      r[b] = std::log(m) - bins.logy[b];
      if (jac != nullptr) {
        dm[static_cast<std::size_t>(np - 1)] = 1.0;
        for (int q = 0; q < np; ++q)
          jac[b * static_cast<std::size_t>(np) + static_cast<std::size_t>(q)] = dm[static_cast<std::size_t>(q)] / m;
      }
    }
    return true;
  };
}

// Start gains: the whitened peak height is g^2 / (2 z)^2 near f_k.
std::vector<ModeStart> psd_start_gains(const std::vector<ModeStart>& starts, const PsdBins& bins, double fref,
                                       double exponent) {
  std::vector<ModeStart> st = starts;
  for (auto& s : st) {
    const std::size_t best = nearest_bin(bins.f, s.freq_hz);
    const double white = bins.y[best] / std::pow(bins.f[best] / fref, exponent);
    s.gain = std::copysign(std::sqrt(white) * 2 * std::max(s.zeta, 1e-3), s.gain == 0 ? 1.0 : s.gain);
  }
  return st;
}

// The model curve, direct term, noise floor, modes and warnings of a converged PSD fit.
void finish_psd(ModalFit& out, const ResidualJacobianFunction& eval, const PsdBins& bins, int modes,
                const ModalFitOptions& o) {
  const int np = 3 * modes + 2;
  const std::size_t n = bins.f.size();
  // Residuals at the solution for the inflation factor and the model curve.
  std::vector<double> p = param_values(out.fit);
  std::vector<double> r(n);
  eval(p.data(), r.data(), nullptr);
  out.model.resize(n);
  for (std::size_t b = 0; b < n; ++b) out.model[b] = std::exp(r[b] + bins.logy[b]) * bins.pmax;
  out.direct_term = p[static_cast<std::size_t>(np - 2)] * std::sqrt(bins.pmax);
  out.noise_floor = p[static_cast<std::size_t>(np - 1)] * bins.pmax;
  const double vif = variance_inflation(r, o.correlation_lags);
  finish(out, modes, vif, o.confidence);
  for (auto& m : out.modes) m.gain *= std::sqrt(bins.pmax);
  // A floor at its lower bound 0 means the spectrum shows no floor above the modes' tails
  // (clean data): that is an answer, not a failure, and nothing a user can act on.
  const bool floor_absent = out.noise_floor == 0;
  for (const auto& w : out.fit.warnings)
    if (!(floor_absent && w.rfind("floor ended on its bound", 0) == 0)) out.warnings.push_back("modal fit: " + w);
}

// The frequency-response bins a fit uses: positive frequency, enough coherence, a response.
struct FrfBins {
  std::vector<double> f;
  std::vector<cd> y;
};

FrfBins usable_frf_bins(const std::vector<double>& freq, const std::vector<cd>& h, const std::vector<double>& coh,
                        double min_coherence) {
  FrfBins bins;
  for (std::size_t b = 0; b < freq.size(); ++b)
    if (freq[b] > 0 && coh[b] >= min_coherence && std::abs(h[b]) > 0) {
      bins.f.push_back(freq[b]);
      bins.y.push_back(h[b]);
    }
  return bins;
}

// Residuals (model - y) / |y| (real and imaginary part per bin) of the kernel-averaged response
// and their Jacobian; the parameters are those of mode_params, then the direct term.
ResidualJacobianFunction frf_residuals(const FrfBins& bins, const KernelGrid& grid, const std::vector<double>& wsum,
                                       int modes) {
  const int np = 3 * modes + 1;
  return [&bins, &grid, &wsum, modes, np](const double* p, double* r, double* jac) -> bool {
    const std::size_t nk = grid.nk;
    std::vector<cd> dh(static_cast<std::size_t>(np)), dm(static_cast<std::size_t>(np));
    for (std::size_t b = 0; b < bins.f.size(); ++b) {
      cd m(0, 0);
      std::fill(dm.begin(), dm.end(), cd(0, 0));
      for (std::size_t j = 0; j < nk; ++j) {
        const double w = grid.wj[b * nk + j] / wsum[b];
        if (w == 0) continue;
        cd hh;
        eval_h(p, modes, grid.fj[b * nk + j], hh, jac != nullptr ? dh.data() : nullptr);
        m += w * hh;
        if (jac != nullptr)
          for (int q = 0; q < np; ++q) dm[static_cast<std::size_t>(q)] += w * dh[static_cast<std::size_t>(q)];
      }
      if (!std::isfinite(m.real()) || !std::isfinite(m.imag())) return false;
      const double scale = 1.0 / std::abs(bins.y[b]);
      const cd e = (m - bins.y[b]) * scale;
      r[2 * b] = e.real();
      r[2 * b + 1] = e.imag();
      if (jac != nullptr)
        for (int q = 0; q < np; ++q) {
          jac[(2 * b) * static_cast<std::size_t>(np) + static_cast<std::size_t>(q)] =
              dm[static_cast<std::size_t>(q)].real() * scale;
          jac[(2 * b + 1) * static_cast<std::size_t>(np) + static_cast<std::size_t>(q)] =
              dm[static_cast<std::size_t>(q)].imag() * scale;
        }
    }
    return true;
  };
}

std::vector<ModeStart> frf_start_gains(const std::vector<ModeStart>& starts, const FrfBins& bins) {
  std::vector<ModeStart> st = starts;
  for (auto& s : st) {
    const std::size_t best = nearest_bin(bins.f, s.freq_hz);
    // At resonance H_k = -j / (2 z): the imaginary part of the data gives g's sign and size.
    const double im = bins.y[best].imag();
    s.gain = -im * 2 * std::max(s.zeta, 1e-3);
    if (s.gain == 0) s.gain = std::abs(bins.y[best]) * 2 * std::max(s.zeta, 1e-3);
  }
  return st;
}

// The model curve, direct term, modes and warnings of a converged frequency-response fit.
void finish_frf(ModalFit& out, const ResidualJacobianFunction& eval, const FrfBins& bins, int modes,
                const ModalFitOptions& o) {
  const int np = 3 * modes + 1;
  const std::size_t n = bins.f.size();
  std::vector<double> p = param_values(out.fit);
  std::vector<double> r(2 * n);
  eval(p.data(), r.data(), nullptr);
  // Inflation from the real parts in frequency order (imaginary parts behave alike).
  std::vector<double> re(n);
  out.model.resize(n);
  for (std::size_t b = 0; b < n; ++b) {
    re[b] = r[2 * b];
    const cd m = bins.y[b] + cd(r[2 * b], r[2 * b + 1]) * std::abs(bins.y[b]);
    out.model[b] = std::abs(m);
  }
  out.direct_term = p[static_cast<std::size_t>(np - 1)];
  finish(out, modes, variance_inflation(re, o.correlation_lags), o.confidence);
  for (const auto& w : out.fit.warnings) out.warnings.push_back("modal fit: " + w);
}
}  // namespace

void inflate_uncertainty(FitResult& fit, double vif, double confidence) {
  const auto& d = fit.diagnostics;
  const double dof = std::max(1.0, (d.num_observations - d.num_parameters) / vif);
  const double tq = t_multiplier(confidence, dof);
  const double s = std::sqrt(vif);
  for (auto& p : fit.params) {
    if (p.fixed || !std::isfinite(p.std_error)) continue;
    p.std_error *= s;
    p.ci95_lo = p.value - tq * p.std_error;
    p.ci95_hi = p.value + tq * p.std_error;
  }
}

std::vector<ModeEstimate> modes_from_params(const std::vector<Param>& params, std::size_t modes, std::size_t stride) {
  std::vector<ModeEstimate> out;
  for (std::size_t k = 0; k < modes; ++k) {
    const auto& pf = params[stride * k];
    const auto& pz = params[stride * k + 1];
    ModeEstimate m;
    m.freq_hz = pf.value;
    m.zeta = pz.value;
    m.gain = params[stride * k + 2].value;
    m.freq_stderr_hz = pf.std_error;
    m.zeta_stderr = pz.std_error;
    m.freq_ci95_lo = pf.ci95_lo;
    m.freq_ci95_hi = pf.ci95_hi;
    m.zeta_ci95_lo = std::max(0.0, pz.ci95_lo);
    m.zeta_ci95_hi = pz.ci95_hi;
    out.push_back(m);
  }
  std::sort(out.begin(), out.end(), [](const ModeEstimate& a, const ModeEstimate& b) { return a.freq_hz < b.freq_hz; });
  return out;
}

ModalFit fit_modal_psd(const std::vector<double>& freq, const std::vector<double>& psd_in,
                       const std::vector<ModeStart>& starts, const SpectralKernel& kernel_in,
                       const ModalFitOptions& o) {
  if (freq.size() != psd_in.size()) throw InputError("modal fit: frequency and PSD arrays differ in length");
  check_starts(starts);
  const SpectralKernel kernel = kernel_in.offsets_hz.empty() ? identity_kernel() : kernel_in;
  const PsdBins bins = usable_psd_bins(freq, psd_in);
  const std::vector<double>& f = bins.f;
  const int modes = static_cast<int>(starts.size());
  const int np = 3 * modes + 2;
  if (static_cast<int>(f.size()) < np + 3)
    throw InputError("modal fit: " + std::to_string(f.size()) + " usable PSD bins for " + std::to_string(modes) +
                     " mode(s); widen the frequency band or use finer resolution");
  const double fref = 0.5 * (f.front() + f.back());
  const KernelGrid grid = kernel_grid(f, kernel, fref, o.excitation_exponent);
  const ResidualJacobianFunction eval = psd_residuals(bins, grid, modes);
  const std::vector<ModeStart> st = psd_start_gains(starts, bins, fref, o.excitation_exponent);
  double floor0 = *std::min_element(bins.y.begin(), bins.y.end()) * 0.1;

  const LsqOptions lo = modal_lsq_options(o.confidence);

  ModalFit out;
  // Stages: everything free; then the floor held; then the floor and direct term held.
  std::string last_error;
  for (int stage = 0; stage < 3; ++stage) {
    const bool floor_free = o.fit_noise_floor && stage == 0;
    const bool direct_free = o.fit_direct_term && stage <= 1;
    LsqProblem prob;
    prob.params = mode_params(st, f.front() * 0.5, f.back() * 1.5, o.max_zeta);
    prob.params.push_back({"direct", "1", 0.0, -1e6, 1e6, !direct_free});
    prob.params.push_back({"floor", "1", o.fit_noise_floor ? floor0 : 0.0, 0.0, 1e6, !floor_free});
    prob.num_residuals = static_cast<int>(f.size());
    prob.residuals_and_jacobian = eval;
    prob.residuals_are_time_ordered = true;
    try {
      out.fit = solve_least_squares("modal_psd", prob, lo);
    } catch (const FitError& e) {
      last_error = e.message();
      continue;
    }
    if (stage > 0)
      out.warnings.push_back("modal fit: " + std::string(stage == 1 ? "noise floor" : "noise floor and direct term") +
                             " held fixed (" + last_error + ")");
    finish_psd(out, eval, bins, modes, o);
    return out;
  }
  throw FitError("modal fit of " + std::to_string(modes) + " mode(s) to the PSD failed: " + last_error);
}

ModalFit fit_modal_frf(const std::vector<double>& freq, const std::vector<cd>& h, const std::vector<double>& coh,
                       double min_coherence, const std::vector<ModeStart>& starts, const SpectralKernel& kernel_in,
                       const ModalFitOptions& o) {
  if (freq.size() != h.size() || freq.size() != coh.size())
    throw InputError("modal fit: frequency, response and coherence arrays differ in length");
  check_starts(starts);
  const SpectralKernel kernel = kernel_in.offsets_hz.empty() ? identity_kernel() : kernel_in;
  const FrfBins bins = usable_frf_bins(freq, h, coh, min_coherence);
  const std::vector<double>& f = bins.f;
  const int modes = static_cast<int>(starts.size());
  const int np = 3 * modes + 1;
  if (static_cast<int>(f.size()) < np + 2)
    throw InputError("modal fit: " + std::to_string(f.size()) + " frequency-response bins with coherence >= " +
                     std::to_string(min_coherence) + " for " + std::to_string(modes) + " mode(s)");
  const double fref = 0.5 * (f.front() + f.back());
  const KernelGrid grid = kernel_grid(f, kernel, fref, o.excitation_exponent);
  std::vector<double> wsum(f.size(), 0.0);
  for (std::size_t b = 0; b < f.size(); ++b)
    for (std::size_t j = 0; j < grid.nk; ++j) wsum[b] += grid.wj[b * grid.nk + j];
  const ResidualJacobianFunction eval = frf_residuals(bins, grid, wsum, modes);
  const std::vector<ModeStart> st = frf_start_gains(starts, bins);
  const LsqOptions lo = modal_lsq_options(o.confidence);
  ModalFit out;
  std::string last_error;
  for (int stage = 0; stage < 2; ++stage) {
    LsqProblem prob;
    prob.params = mode_params(st, f.front() * 0.5, f.back() * 1.5, o.max_zeta);
    prob.params.push_back({"direct", "1", 0.0, -1e6, 1e6, !(o.fit_direct_term && stage == 0)});
    prob.num_residuals = static_cast<int>(2 * f.size());
    prob.residuals_and_jacobian = eval;
    prob.residuals_are_time_ordered = false;
    try {
      out.fit = solve_least_squares("modal_frf", prob, lo);
    } catch (const FitError& e) {
      last_error = e.message();
      continue;
    }
    if (stage > 0) out.warnings.push_back("modal fit: direct term held at 0 (" + last_error + ")");
    finish_frf(out, eval, bins, modes, o);
    return out;
  }
  throw FitError("modal fit of " + std::to_string(modes) + " mode(s) to the frequency response failed: " + last_error);
}

}  // namespace tunekit::fitting
