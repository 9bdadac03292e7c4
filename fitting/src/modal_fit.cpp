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
  const auto& d = out.fit.diagnostics;
  const double dof = std::max(1.0, (d.num_observations - d.num_parameters) / vif);
  const double tq = t_multiplier(confidence, dof);
  const double s = std::sqrt(vif);
  for (auto& p : out.fit.params) {
    if (p.fixed || !std::isfinite(p.std_error)) continue;
    p.std_error *= s;
    p.ci95_lo = p.value - tq * p.std_error;
    p.ci95_hi = p.value + tq * p.std_error;
  }
  out.modes.clear();
  for (int k = 0; k < modes; ++k) {
    const auto& pf = out.fit.params[static_cast<std::size_t>(3 * k)];
    const auto& pz = out.fit.params[static_cast<std::size_t>(3 * k + 1)];
    const auto& pg = out.fit.params[static_cast<std::size_t>(3 * k + 2)];
    ModeEstimate m;
    m.freq_hz = pf.value;
    m.zeta = pz.value;
    m.gain = pg.value;
    m.freq_stderr_hz = pf.std_error;
    m.zeta_stderr = pz.std_error;
    m.freq_ci95_lo = pf.ci95_lo;
    m.freq_ci95_hi = pf.ci95_hi;
    m.zeta_ci95_lo = std::max(0.0, pz.ci95_lo);
    m.zeta_ci95_hi = pz.ci95_hi;
    out.modes.push_back(m);
  }
  std::sort(out.modes.begin(), out.modes.end(),
            [](const ModeEstimate& a, const ModeEstimate& b) { return a.freq_hz < b.freq_hz; });
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

}  // namespace

ModalFit fit_modal_psd(const std::vector<double>& freq, const std::vector<double>& psd_in,
                       const std::vector<ModeStart>& starts, const SpectralKernel& kernel_in,
                       const ModalFitOptions& o) {
  if (freq.size() != psd_in.size()) throw InputError("modal fit: frequency and PSD arrays differ in length");
  check_starts(starts);
  const SpectralKernel kernel = kernel_in.offsets_hz.empty() ? identity_kernel() : kernel_in;
  std::vector<double> f, y;
  double pmax = 0;
  for (std::size_t b = 0; b < freq.size(); ++b)
    if (psd_in[b] > 0 && std::isfinite(psd_in[b]) && freq[b] > 0) {
      f.push_back(freq[b]);
      y.push_back(psd_in[b]);
      pmax = std::max(pmax, psd_in[b]);
    }
  const int modes = static_cast<int>(starts.size());
  const int np = 3 * modes + 2;
  if (static_cast<int>(f.size()) < np + 3)
    throw InputError("modal fit: " + std::to_string(f.size()) + " usable PSD bins for " + std::to_string(modes) +
                     " mode(s); widen the frequency band or use finer resolution");
  for (double& v : y) v /= pmax;  // fit in relative units; gains and floor are scaled back
  const double fref = 0.5 * (f.front() + f.back());
  std::vector<double> logy(y.size());
  for (std::size_t b = 0; b < y.size(); ++b) logy[b] = std::log(y[b]);

  // Precompute kernel abscissae and excitation weights per bin.
  const std::size_t nk = kernel.offsets_hz.size();
  std::vector<double> fj(f.size() * nk), wj(f.size() * nk);
  for (std::size_t b = 0; b < f.size(); ++b)
    for (std::size_t j = 0; j < nk; ++j) {
      const double x = f[b] + kernel.offsets_hz[j];
      fj[b * nk + j] = x;
      wj[b * nk + j] = x > 0 ? kernel.weights[j] * std::pow(x / fref, o.excitation_exponent) : 0.0;
    }

  auto eval = [&, modes, np](const double* p, double* r, double* jac) -> bool {
    std::vector<cd> dh(static_cast<std::size_t>(3 * modes + 1));
    std::vector<double> dm(static_cast<std::size_t>(np));
    for (std::size_t b = 0; b < f.size(); ++b) {
      double m = p[np - 1];
      std::fill(dm.begin(), dm.end(), 0.0);
      for (std::size_t j = 0; j < nk; ++j) {
        const double w = wj[b * nk + j];
        if (w == 0) continue;
        cd h;
        eval_h(p, modes, fj[b * nk + j], h, jac != nullptr ? dh.data() : nullptr);
        m += w * std::norm(h);
        if (jac != nullptr)
          for (int q = 0; q < 3 * modes + 1; ++q)
            dm[static_cast<std::size_t>(q)] += w * 2 * std::real(std::conj(h) * dh[static_cast<std::size_t>(q)]);
      }
      if (!(m > 0) || !std::isfinite(m)) return false;
      r[b] = std::log(m) - logy[b];
      if (jac != nullptr) {
        dm[static_cast<std::size_t>(np - 1)] = 1.0;
        for (int q = 0; q < np; ++q)
          jac[b * static_cast<std::size_t>(np) + static_cast<std::size_t>(q)] = dm[static_cast<std::size_t>(q)] / m;
      }
    }
    return true;
  };

  // Start gains: the whitened peak height is g^2 / (2 z)^2 near f_k.
  std::vector<ModeStart> st = starts;
  for (auto& s : st) {
    std::size_t best = 0;
    for (std::size_t b = 0; b < f.size(); ++b)
      if (std::abs(f[b] - s.freq_hz) < std::abs(f[best] - s.freq_hz)) best = b;
    const double white = y[best] / std::pow(f[best] / fref, o.excitation_exponent);
    s.gain = std::copysign(std::sqrt(white) * 2 * std::max(s.zeta, 1e-3), s.gain == 0 ? 1.0 : s.gain);
  }
  double floor0 = *std::min_element(y.begin(), y.end()) * 0.1;

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
    // Residuals at the solution for the inflation factor and the model curve.
    std::vector<double> p;
    for (const auto& q : out.fit.params) p.push_back(q.value);
    std::vector<double> r(f.size());
    eval(p.data(), r.data(), nullptr);
    out.model.resize(f.size());
    for (std::size_t b = 0; b < f.size(); ++b) out.model[b] = std::exp(r[b] + logy[b]) * pmax;
    out.direct_term = p[static_cast<std::size_t>(np - 2)] * std::sqrt(pmax);
    out.noise_floor = p[static_cast<std::size_t>(np - 1)] * pmax;
    const double vif = variance_inflation(r, o.correlation_lags);
    finish(out, modes, vif, o.confidence);
    for (auto& m : out.modes) m.gain *= std::sqrt(pmax);
    // A floor at its lower bound 0 means the spectrum shows no floor above the modes' tails
    // (clean data): that is an answer, not a failure, and nothing a user can act on.
    const bool floor_absent = out.noise_floor == 0;
    for (const auto& w : out.fit.warnings)
      if (!(floor_absent && w.rfind("floor ended on its bound", 0) == 0)) out.warnings.push_back("modal fit: " + w);
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
  std::vector<double> f;
  std::vector<cd> y;
  for (std::size_t b = 0; b < freq.size(); ++b)
    if (freq[b] > 0 && coh[b] >= min_coherence && std::abs(h[b]) > 0) {
      f.push_back(freq[b]);
      y.push_back(h[b]);
    }
  const int modes = static_cast<int>(starts.size());
  const int np = 3 * modes + 1;
  if (static_cast<int>(f.size()) < np + 2)
    throw InputError("modal fit: " + std::to_string(f.size()) + " frequency-response bins with coherence >= " +
                     std::to_string(min_coherence) + " for " + std::to_string(modes) + " mode(s)");
  const double fref = 0.5 * (f.front() + f.back());
  const std::size_t nk = kernel.offsets_hz.size();
  std::vector<double> fj(f.size() * nk), wj(f.size() * nk), wsum(f.size(), 0.0);
  for (std::size_t b = 0; b < f.size(); ++b)
    for (std::size_t j = 0; j < nk; ++j) {
      const double x = f[b] + kernel.offsets_hz[j];
      fj[b * nk + j] = x;
      wj[b * nk + j] = x > 0 ? kernel.weights[j] * std::pow(x / fref, o.excitation_exponent) : 0.0;
      wsum[b] += wj[b * nk + j];
    }
  auto eval = [&, modes, np](const double* p, double* r, double* jac) -> bool {
    std::vector<cd> dh(static_cast<std::size_t>(np)), dm(static_cast<std::size_t>(np));
    for (std::size_t b = 0; b < f.size(); ++b) {
      cd m(0, 0);
      std::fill(dm.begin(), dm.end(), cd(0, 0));
      for (std::size_t j = 0; j < nk; ++j) {
        const double w = wj[b * nk + j] / wsum[b];
        if (w == 0) continue;
        cd hh;
        eval_h(p, modes, fj[b * nk + j], hh, jac != nullptr ? dh.data() : nullptr);
        m += w * hh;
        if (jac != nullptr)
          for (int q = 0; q < np; ++q) dm[static_cast<std::size_t>(q)] += w * dh[static_cast<std::size_t>(q)];
      }
      if (!std::isfinite(m.real()) || !std::isfinite(m.imag())) return false;
      const double scale = 1.0 / std::abs(y[b]);
      const cd e = (m - y[b]) * scale;
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
  std::vector<ModeStart> st = starts;
  for (auto& s : st) {
    std::size_t best = 0;
    for (std::size_t b = 0; b < f.size(); ++b)
      if (std::abs(f[b] - s.freq_hz) < std::abs(f[best] - s.freq_hz)) best = b;
    // At resonance H_k = -j / (2 z): the imaginary part of the data gives g's sign and size.
    const double im = y[best].imag();
    s.gain = -im * 2 * std::max(s.zeta, 1e-3);
    if (s.gain == 0) s.gain = std::abs(y[best]) * 2 * std::max(s.zeta, 1e-3);
  }
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
    std::vector<double> p;
    for (const auto& q : out.fit.params) p.push_back(q.value);
    std::vector<double> r(2 * f.size());
    eval(p.data(), r.data(), nullptr);
    // Inflation from the real parts in frequency order (imaginary parts behave alike).
    std::vector<double> re(f.size());
    out.model.resize(f.size());
    for (std::size_t b = 0; b < f.size(); ++b) {
      re[b] = r[2 * b];
      const cd m = y[b] + cd(r[2 * b], r[2 * b + 1]) * std::abs(y[b]);
      out.model[b] = std::abs(m);
    }
    out.direct_term = p[static_cast<std::size_t>(np - 1)];
    finish(out, modes, variance_inflation(re, o.correlation_lags), o.confidence);
    for (const auto& w : out.fit.warnings) out.warnings.push_back("modal fit: " + w);
    return out;
  }
  throw FitError("modal fit of " + std::to_string(modes) + " mode(s) to the frequency response failed: " + last_error);
}

}  // namespace tunekit::fitting
