#include "tunekit/fitting/transfer_function.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"
#include "number_text.hpp"

namespace tunekit::fitting {
namespace {

constexpr double kPi = std::numbers::pi;
// Ljung-Box p-value below which an output-error fit's intervals are widened for correlated
// residuals (the pooled step fit's threshold for its cluster-robust covariance).
constexpr double kWhitenessWidenP = 0.01;

std::vector<double> polymul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}

std::complex<double> polyval(const std::vector<double>& p, std::complex<double> s) {
  std::complex<double> v = 0;
  for (double c : p) v = v * s + c;
  return v;
}

// A transfer function ready for a sampled simulation: made monic and put in controllable
// canonical form x' = A x + e1 u, y = C x + D u (n states), its delay split into whole samples
// and the fraction of a sample left over (0 when it is below 1e-12 samples).
struct SampledForm {
  int n = 0;
  double D = 0;
  Eigen::MatrixXd A;
  Eigen::VectorXd C;
  long d_whole = 0;
  double frac = 0;
};

// `method` ("ZOH", "FOH") names the simulation in the InputError for a bad model or interval.
SampledForm sampled_form(const TransferFunction& tf, double dt, const char* method) {
  const auto& num = tf.num;
  const auto& den = tf.den;
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError(fmt::format("{} simulation: the sample interval must be positive", method));
  if (den.empty() || den.front() == 0 || num.empty() || num.size() > den.size())
    throw InputError(fmt::format("{} simulation: the transfer function is empty or improper", method));
  if (!(tf.delay_s >= 0)) throw InputError(fmt::format("{} simulation: negative delay", method));
  SampledForm sf;
  sf.n = static_cast<int>(den.size()) - 1;
  const int n = sf.n;
  // Monic denominator; numerator padded to n + 1 coefficients.
  std::vector<double> a(den.size()), b(den.size(), 0.0);
  for (std::size_t i = 0; i < den.size(); ++i) a[i] = den[i] / den[0];
  for (std::size_t i = 0; i < num.size(); ++i) b[den.size() - num.size() + i] = num[i] / den[0];
  sf.D = b[0];
  sf.d_whole = static_cast<long>(std::floor(tf.delay_s / dt + 1e-12));
  sf.frac = tf.delay_s - static_cast<double>(sf.d_whole) * dt;
  if (sf.frac < 1e-12 * dt) sf.frac = 0;
  sf.A = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) sf.A(0, j) = -a[static_cast<std::size_t>(j) + 1];
  for (int i = 1; i < n; ++i) sf.A(i, i - 1) = 1.0;
  sf.C.resize(n);
  for (int i = 0; i < n; ++i) sf.C(i) = b[static_cast<std::size_t>(i) + 1] - a[static_cast<std::size_t>(i) + 1] * sf.D;
  return sf;
}

}  // namespace

std::complex<double> TransferFunction::response(double freq_hz) const {
  const std::complex<double> s(0.0, 2 * kPi * freq_hz);
  std::complex<double> h = polyval(num, s) / polyval(den, s);
  if (delay_s != 0) h *= std::exp(-s * delay_s);
  return h;
}

double TransferFunction::dc_gain() const { return num.back() / den.back(); }

std::vector<double> TransferFunction::simulate_zoh(std::span<const double> u, double dt) const {
  const SampledForm sf = sampled_form(*this, dt, "ZOH");
  const int n = sf.n;
  const double D = sf.D, frac = sf.frac;
  const long d_whole = sf.d_whole;
  const Eigen::MatrixXd& A = sf.A;
  const Eigen::VectorXd& C = sf.C;
  const std::size_t N = u.size();
  std::vector<double> y(N, 0.0);
  auto uat = [&](long k) { return (k >= 0 && k < static_cast<long>(N)) ? u[static_cast<std::size_t>(k)] : 0.0; };
  if (n == 0) {
    for (std::size_t k = 0; k < N; ++k)
      y[k] = D * (frac > 0 ? uat(static_cast<long>(k) - d_whole - 1) : uat(static_cast<long>(k) - d_whole));
    return y;
  }
  // Phi(h) and Gamma(h) = int_0^h e^{As} ds B from one matrix exponential of [[A, B], [0, 0]] h.
  auto discretize = [&](double h, Eigen::MatrixXd& Phi, Eigen::VectorXd& Gam) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 1, n + 1);
    M.topLeftCorner(n, n) = A * h;
    M(0, n) = h;  // B = e1
    const Eigen::MatrixXd E = M.exp();
    Phi = E.topLeftCorner(n, n);
    Gam = E.topRightCorner(n, 1);
  };
  Eigen::MatrixXd Phi;
  Eigen::VectorXd G0, G1 = Eigen::VectorXd::Zero(n);
  discretize(dt, Phi, G0);
  if (frac > 0) {
    Eigen::MatrixXd Pa, Pb;
    Eigen::VectorXd Ga, Gb;
    discretize(frac, Pa, Ga);       // the part of the interval still at the older input
    discretize(dt - frac, Pb, Gb);  // the rest, at the newer input
    G1 = Pb * Ga;
    G0 = Gb;
  }
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (!std::isfinite(Phi(i, j))) throw InputError("ZOH simulation: the discretization is not finite");
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), xn(n);
  for (std::size_t k = 0; k < N; ++k) {
    const long kk = static_cast<long>(k);
    const double u_new = uat(kk - d_whole), u_old = uat(kk - d_whole - 1);
    y[k] = C.dot(x) + D * (frac > 0 ? u_old : u_new);
    xn.noalias() = Phi * x;
    xn += G0 * u_new;
    if (frac > 0) xn += G1 * u_old;
    x = xn;
  }
  return y;
}

TfStructure parse_tf_structure(const std::string& text) {
  TfStructure s;
  int p = -1, z = -1;
  char extra = 0;
  if (std::sscanf(text.c_str(), "%d,%d%c", &p, &z, &extra) != 2)
    throw InputError("transfer-function structure '" + text + "': expected POLES,ZEROS such as 2,0");
  if (p < 1 || p > 3 || z < 0 || z > 2 || z > p)
    throw InputError("transfer-function structure '" + text + "': 1 to 3 poles and 0 to 2 zeros, zeros <= poles");
  s.poles = p;
  s.zeros = z;
  return s;
}

std::string tf_model_name(const TfStructure& s) {
  return "tf(" + std::to_string(s.poles) + "," + std::to_string(s.zeros) + ")" + (s.delay ? "+delay" : "");
}

std::vector<std::string> tf_param_names(const TfStructure& s) {
  std::vector<std::string> n{"K"};
  if (s.poles >= 2) {
    n.push_back("fn_hz");
    n.push_back("zeta");
  }
  if (s.poles % 2 == 1) n.push_back("tau_s");
  if (s.zeros == 1) n.push_back("tz_s");
  if (s.zeros == 2) {
    n.push_back("b1_s");
    n.push_back("b2_s2");
  }
  if (s.delay) n.push_back("theta_s");
  return n;
}

TransferFunction tf_from_params(const TfStructure& s, const double* p) {
  TransferFunction tf;
  std::size_t i = 0;
  const double K = p[i++];
  std::vector<double> den{1.0};
  if (s.poles >= 2) {
    const double wn = 2 * kPi * p[i];
    const double zeta = p[i + 1];
    i += 2;
    den = polymul(den, {1.0 / (wn * wn), 2 * zeta / wn, 1.0});
  }
  if (s.poles % 2 == 1) den = polymul(den, {p[i++], 1.0});
  std::vector<double> num{1.0};
  if (s.zeros == 1) num = {p[i++], 1.0};
  if (s.zeros == 2) {
    num = {p[i + 1], p[i], 1.0};
    i += 2;
  }
  for (double& c : num) c *= K;
  // Drop leading zero coefficients of the numerator (b2 = 0 and so on) but keep one.
  while (num.size() > 1 && num.front() == 0) num.erase(num.begin());
  tf.num = num;
  tf.den = den;
  if (s.delay) tf.delay_s = p[i++];
  return tf;
}

TransferFunction tf_from_fit(const TfStructure& s, const FitResult& f) {
  std::vector<double> p;
  for (const auto& n : tf_param_names(s)) p.push_back(f.value(n));
  return tf_from_params(s, p.data());
}

double h1_sigma(std::complex<double> h, double coherence, std::size_t segments) {
  const double g2 = std::clamp(coherence, 1e-6, 0.9999);
  return std::abs(h) * std::sqrt((1 - g2) / (2.0 * static_cast<double>(std::max<std::size_t>(segments, 1)) * g2));
}

namespace {

std::vector<ParamSpec> tf_specs(const TfStructure& s, const std::vector<double>& start, const std::string& gain_unit) {
  const auto names = tf_param_names(s);
  std::vector<ParamSpec> specs;
  for (std::size_t i = 0; i < names.size(); ++i) {
    ParamSpec ps{names[i], "1", start[i]};
    const auto& n = names[i];
    if (n == "K") ps.unit = gain_unit;
    else if (n == "fn_hz") {
      ps.unit = "Hz";
      ps.lower = 1e-9;
    } else if (n == "zeta") {
      ps.lower = 1e-4;
      ps.upper = 100;
    } else if (n == "tau_s") {
      ps.unit = "s";
      ps.lower = 1e-12;
    } else if (n == "tz_s" || n == "b1_s") {
      ps.unit = "s";
    } else if (n == "b2_s2") {
      ps.unit = "s^2";
    } else if (n == "theta_s") {
      ps.unit = "s";
      ps.lower = 0;
    }
    specs.push_back(ps);
  }
  return specs;
}

}  // namespace

FitResult fit_tf_frf(std::span<const double> freq_hz, std::span<const std::complex<double>> h,
                     std::span<const double> sigma, const TfStructure& s, const std::string& gain_unit) {
  const std::size_t m = freq_hz.size();
  if (h.size() != m || sigma.size() != m) throw InputError("TF fit: frequency, response and sigma lengths differ");
  const std::size_t k = tf_param_names(s).size();
  if (2 * m <= k)
    throw InputError("TF fit: " + std::to_string(m) + " frequency points are too few for " + std::to_string(k) +
                     " parameters");
  for (std::size_t i = 0; i < m; ++i)
    if (!(freq_hz[i] > 0) || !std::isfinite(h[i].real()) || !std::isfinite(h[i].imag()) || !(sigma[i] > 0))
      throw InputError("TF fit: frequencies and uncertainties must be positive and responses finite");
  const std::vector<double> f(freq_hz.begin(), freq_hz.end()), w(sigma.begin(), sigma.end());
  const std::vector<std::complex<double>> H(h.begin(), h.end());
  LsqProblem prob;
  prob.num_residuals = static_cast<int>(2 * m);
  prob.residuals_are_time_ordered = false;
  for (std::size_t i = 0; i < m; ++i) {
    prob.observed.push_back(H[i].real() / w[i]);
    prob.observed.push_back(H[i].imag() / w[i]);
  }
  prob.residuals = [s, f, w, H](const double* p, double* r) {
    const auto tf = tf_from_params(s, p);
    for (std::size_t i = 0; i < f.size(); ++i) {
      const auto e = (tf.response(f[i]) - H[i]) / w[i];
      if (!std::isfinite(e.real()) || !std::isfinite(e.imag())) return false;
      r[2 * i] = e.real();
      r[2 * i + 1] = e.imag();
    }
    return true;
  };
  // Start grid: gain from the lowest frequency, poles spread over the band.
  const auto [fmin_it, fmax_it] = std::minmax_element(f.begin(), f.end());
  const double fmin = *fmin_it, fmax = *fmax_it;
  const std::size_t i_low = static_cast<std::size_t>(fmin_it - f.begin());
  const double K0 = (H[i_low].real() >= 0 ? 1.0 : -1.0) * std::abs(H[i_low]);
  auto logspace = [](double lo, double hi, int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(lo * std::pow(hi / lo, n == 1 ? 0.5 : double(i) / (n - 1)));
    return v;
  };
  std::vector<double> fn_grid{1.0}, zeta_grid{1.0}, tau_grid{0.0};
  if (s.poles >= 2) {
    fn_grid = logspace(fmin, fmax, 7);
    zeta_grid = {0.1, 0.4, 1.2};
  }
  if (s.poles % 2 == 1) {
    tau_grid.clear();
    for (double fc : logspace(fmin, fmax, 5)) tau_grid.push_back(1.0 / (2 * kPi * fc));
  }
  LsqOptions scan;
  scan.compute_covariance = false;
  scan.require_convergence = false;
  scan.max_iterations = 100;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_p;
  std::string last_error;
  for (double fn : fn_grid)
    for (double zeta : zeta_grid)
      for (double tau : tau_grid) {
        std::vector<double> p{K0};
        if (s.poles >= 2) {
          p.push_back(fn);
          p.push_back(zeta);
        }
        if (s.poles % 2 == 1) p.push_back(tau);
        if (s.zeros == 1) p.push_back(0.01 / (2 * kPi * fmax));
        if (s.zeros == 2) {
          p.push_back(0.01 / (2 * kPi * fmax));
          p.push_back(0.0);
        }
        if (s.delay) p.push_back(0.0);
        prob.params = tf_specs(s, p, gain_unit);
        try {
          const auto r = solve_least_squares(tf_model_name(s), prob, scan);
          if (r.diagnostics.rss < best) {
            best = r.diagnostics.rss;
            best_p.clear();
            for (const auto& q : r.params) best_p.push_back(q.value);
          }
        } catch (const FitError& e) {
          last_error = e.message();
        }
      }
  if (best_p.empty()) throw FitError(tf_model_name(s) + ": no start value led to a fit (" + last_error + ")");
  prob.params = tf_specs(s, best_p, gain_unit);
  auto r = solve_least_squares(tf_model_name(s), prob);
  if (s.poles >= 2) {
    const double zeta = r.value("zeta");
    if (zeta > 1) r.warnings.push_back("zeta = " + text::g4(zeta) + " > 1: fn_hz/zeta describe two real poles");
  }
  return r;
}

std::vector<double> TransferFunction::simulate_foh(std::span<const double> u, double dt) const {
  const SampledForm sf = sampled_form(*this, dt, "FOH");
  const int n = sf.n;
  const double D = sf.D, frac = sf.frac;
  const long d_whole = sf.d_whole;
  const Eigen::MatrixXd& A = sf.A;
  const Eigen::VectorXd& C = sf.C;
  const auto N = static_cast<long>(u.size());
  std::vector<double> y(u.size(), 0.0);
  const double w = frac / dt;  // the delayed input at k dt lies this far back from sample k - d_whole
  auto uat = [&](long k) { return k < 0 ? 0.0 : u[static_cast<std::size_t>(std::min(k, N - 1))]; };
  // The delayed input at k dt, and at k dt + frac (where it passes through sample k - d_whole).
  auto u_grid = [&](long k) { return uat(k - d_whole) - w * (uat(k - d_whole) - uat(k - d_whole - 1)); };
  if (n == 0) {
    for (long k = 0; k < N; ++k) y[static_cast<std::size_t>(k)] = D * u_grid(k);
    return y;
  }
  // Over a span h with the input going linearly from v0 to v1: x(h) = Phi x + G v0 + L (v1 - v0),
  // from one matrix exponential of [[A, B, 0], [0, 0, 1], [0, 0, 0]] h (B = e1).
  struct Hold {
    Eigen::MatrixXd Phi;
    Eigen::VectorXd G, L;
  };
  auto hold = [&](double h) {
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 2, n + 2);
    M.topLeftCorner(n, n) = A * h;
    M(0, n) = h;
    M(n, n + 1) = h;
    const Eigen::MatrixXd E = M.exp();
    if (!E.allFinite()) throw InputError("FOH simulation: the discretization is not finite");
    return Hold{E.topLeftCorner(n, n), E.block(0, n, n, 1), E.block(0, n + 1, n, 1) / h};
  };
  const Hold first = hold(frac > 0 ? frac : dt), second = frac > 0 ? hold(dt - frac) : Hold{};
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n), xn(n);
  for (long k = 0; k < N; ++k) {
    const double v0 = u_grid(k), v1 = u_grid(k + 1);
    y[static_cast<std::size_t>(k)] = C.dot(x) + D * v0;
    if (frac > 0) {
      const double vm = uat(k - d_whole);  // at k dt + frac
      xn.noalias() = first.Phi * x;
      xn += first.G * v0 + first.L * (vm - v0);
      x.noalias() = second.Phi * xn;
      x += second.G * vm + second.L * (v1 - vm);
    } else {
      xn.noalias() = first.Phi * x;
      xn += first.G * v0 + first.L * (v1 - v0);
      x = xn;
    }
  }
  return y;
}

namespace {

/// Residuals of an output-error fit that fail the whiteness test say the model does not follow
/// the record exactly (a plant that is not linear over the excitation's range, a feed the model
/// does not see): consecutive errors are correlated and s^2 (J^T J)^-1 is too sure. Its variances
/// are multiplied by the residuals' variance factor (residual_variance_factor), the degrees of
/// freedom divided by it, as the whole-record liquefier model does.
void widen_for_correlated_residuals(FitResult& f, const LsqProblem& prob, const LsqOptions& o) {
  if (!o.compute_covariance || o.absolute_sigma || !(f.diagnostics.whiteness_p < kWhitenessWidenP)) return;
  std::vector<double> p;
  for (const auto& prm : f.params) p.push_back(prm.value);
  std::vector<double> r(static_cast<std::size_t>(prob.num_residuals));
  if (!prob.residuals(p.data(), r.data())) return;
  const double factor = residual_variance_factor(r);
  if (!(factor > 1)) return;
  const double dof = std::max(1.0, (f.diagnostics.num_observations - f.diagnostics.num_parameters) / factor);
  const double tq = t_multiplier(o.confidence, dof);
  for (auto& prm : f.params) {
    if (prm.fixed || !std::isfinite(prm.std_error)) continue;
    prm.std_error *= std::sqrt(factor);
    prm.ci95_lo = prm.value - tq * prm.std_error;
    prm.ci95_hi = prm.value + tq * prm.std_error;
    prm.ci95_method = fmt::format("wald, widened for correlated residuals (variance factor {:.3g})", factor);
  }
  for (double& c : f.covariance) c *= factor;
}

}  // namespace

InterSample parse_inter_sample(const std::string& name) {
  if (name == "auto") return InterSample::automatic;
  if (name == "hold") return InterSample::hold;
  if (name == "centred" || name == "centered") return InterSample::hold_centred;
  if (name == "bandlimited") return InterSample::band_limited;
  throw InputError("unknown inter-sample behaviour '" + name + "' (expected auto, hold, centred or bandlimited)");
}

std::string to_string(InterSample s) {
  switch (s) {
    case InterSample::automatic: return "auto";
    case InterSample::hold: return "hold";
    case InterSample::hold_centred: return "centred";
    case InterSample::band_limited: return "bandlimited";
  }
  return "auto";
}

FitResult fit_tf_output_error(std::span<const double> u, std::span<const double> y, double dt, const TfStructure& s,
                              const FitResult& start, const std::string& gain_unit, const LsqOptions& options,
                              InterSample inter_sample) {
  if (u.size() != y.size()) throw InputError("output-error fit: input and output lengths differ");
  const auto names = tf_param_names(s);
  if (y.size() < 4 * (names.size() + 1))
    throw InputError("output-error fit: too few samples (" + std::to_string(y.size()) + ")");
  std::vector<double> du(u.size());
  for (std::size_t i = 0; i < u.size(); ++i) du[i] = u[i] - u[0];
  const std::vector<double> yv(y.begin(), y.end());
  std::vector<double> p0;
  for (const auto& n : names) p0.push_back(start.value(n));
  auto specs = tf_specs(s, p0, gain_unit);
  specs.push_back({"y0", "1", yv.front()});
  LsqProblem prob;
  prob.params = specs;
  prob.num_residuals = static_cast<int>(yv.size());
  prob.observed = yv;
  const std::size_t k = names.size();
  if (inter_sample == InterSample::automatic) {
    // An input that repeats its value over most samples is a staircase, not band-limited.
    std::size_t repeats = 0;
    for (std::size_t i = 1; i < du.size(); ++i)
      if (du[i] == du[i - 1]) ++repeats;
    inter_sample = 2 * repeats > du.size() ? InterSample::hold_centred : InterSample::band_limited;
  }
  // Linear interpolation between the samples of a band-limited input attenuates a component at
  // f by sinc^2(f dt) (0.8 % at a twentieth of the sampling rate), which the gain and the poles
  // would absorb. The three-tap filter [-1/12, 7/6, -1/12] (response 1 + (1 - cos 2 pi f dt) / 6)
  // undoes that to fourth order in f dt.
  if (inter_sample == InterSample::band_limited && du.size() >= 3) {
    std::vector<double> pre(du.size());
    for (std::size_t i = 0; i < du.size(); ++i) {
      const double l = du[i == 0 ? 0 : i - 1], r = du[i + 1 < du.size() ? i + 1 : i];
      pre[i] = (7.0 / 6.0) * du[i] - (l + r) / 12.0;
    }
    du = std::move(pre);
  }
  // A centred sample held from its time stamp would come half a sample late and the dead time
  // would read short by as much; linear between the samples, each change is centred where it
  // belongs, and the output is smooth in the dead time (a held input's output has a kink
  // wherever the delay crosses a sample, where a minimum often sits).
  const bool held = inter_sample == InterSample::hold;
  prob.residuals = [s, du, yv, dt, k, held](const double* p, double* r) {
    const auto tf = tf_from_params(s, p);
    std::vector<double> sim;
    try {
      sim = held ? tf.simulate_zoh(du, dt) : tf.simulate_foh(du, dt);
    } catch (const InputError&) {
      return false;
    }
    for (std::size_t i = 0; i < yv.size(); ++i) {
      r[i] = sim[i] + p[k] - yv[i];
      if (!std::isfinite(r[i])) return false;
    }
    return true;
  };
  FitResult f = solve_least_squares(tf_model_name(s) + " output error", prob, options);
  widen_for_correlated_residuals(f, prob, options);
  return f;
}

}  // namespace tunekit::fitting
