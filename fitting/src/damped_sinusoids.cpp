#include "tunekit/fitting/damped_sinusoids.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <complex>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

std::vector<PencilComponent> matrix_pencil(const std::vector<double>& y, double fs_hz, int order, int pencil) {
  using Mat = Eigen::MatrixXd;
  const int n = static_cast<int>(y.size());
  if (order < 1) throw InputError("matrix pencil: the order must be at least 1");
  int L = pencil > 0 ? pencil : std::min(n / 3, 100);
  L = std::max(L, order + 1);
  if (n < 2 * L + 1 || !(fs_hz > 0))
    throw InputError(fmt::format("matrix pencil: {} samples are too few for {} exponentials", n, order));
  // Hankel data matrix Y (n-L) x (L+1); its dominant right singular vectors span the signal.
  Mat Y(n - L, L + 1);
  for (int r = 0; r < n - L; ++r)
    for (int c = 0; c <= L; ++c) Y(r, c) = y[static_cast<std::size_t>(r + c)];
  Eigen::BDCSVD<Mat> svd(Y, Eigen::ComputeThinV);
  const Mat V = svd.matrixV().leftCols(order);
  const Mat V1 = V.topRows(L);     // rows 0..L-1
  const Mat V2 = V.bottomRows(L);  // rows 1..L
  // The poles z are the eigenvalues of pinv(V1) V2 (order x order).
  const Mat A = V1.completeOrthogonalDecomposition().solve(V2);
  Eigen::EigenSolver<Mat> es(A);
  if (es.info() != Eigen::Success) throw FitError("matrix pencil: the eigenvalue problem did not converge");
  const Eigen::VectorXcd z = es.eigenvalues();

  // Complex amplitudes h from the Vandermonde system y_k = sum h_i z_i^k (least squares).
  Eigen::MatrixXcd Z(n, order);
  for (int i = 0; i < order; ++i) {
    std::complex<double> p(1.0, 0.0);
    for (int k = 0; k < n; ++k) {
      Z(k, i) = p;
      p *= z(i);
    }
  }
  Eigen::VectorXcd yc(n);
  for (int k = 0; k < n; ++k) yc(k) = y[static_cast<std::size_t>(k)];
  // Distinct poles make Z full rank: a column-pivoted QR solves it as the complete orthogonal
  // decomposition did, at two thirds of this file's compile time.
  const Eigen::VectorXcd h = Z.colPivHouseholderQr().solve(yc);

  std::vector<PencilComponent> out;
  for (int i = 0; i < order; ++i) {
    const double wd = std::arg(z(i)) * fs_hz;  // rad/s
    if (!(wd > 0)) continue;                   // conjugate twin or a real (non-oscillating) pole
    const double sigma = -std::log(std::abs(z(i))) * fs_hz;
    const double wn = std::hypot(wd, sigma);
    PencilComponent c;
    c.freq_hz = wn / (2 * std::numbers::pi);
    c.zeta = sigma / wn;
    c.amplitude = 2 * std::abs(h(i));
    c.phase_rad = std::arg(h(i));
    if (std::isfinite(c.freq_hz) && std::isfinite(c.zeta) && std::isfinite(c.amplitude)) out.push_back(c);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.amplitude > b.amplitude; });
  return out;
}

namespace {

constexpr double kMinDampedZeta = 1e-5;
constexpr double kMaxDampedZeta = 0.9;

// The upper bound of a component's damping ratio.
double max_zeta_of(const PencilComponent& s) {
  return s.max_zeta > 0 ? std::min(s.max_zeta, kMaxDampedZeta) : kMaxDampedZeta;
}

// Start dampings: the components' own, inside the lower half of their bounds.
std::vector<double> start_dampings(const std::vector<PencilComponent>& start) {
  std::vector<double> z0(start.size());
  for (std::size_t i = 0; i < start.size(); ++i)
    z0[i] = std::clamp(start[i].zeta, 2 * kMinDampedZeta, 0.5 * max_zeta_of(start[i]));
  return z0;
}

// Amplitudes and offset enter linearly: their least-squares values for the start frequencies and
// dampings z0 (one variable-projection step), as a_0, b_0, a_1, ..., offset.
Eigen::VectorXd linear_start(const std::vector<double>& y, double fs_hz, const std::vector<PencilComponent>& start,
                             const std::vector<double>& z0) {
  const int m = static_cast<int>(y.size());
  const int nc = static_cast<int>(start.size());
  Eigen::MatrixXd D(m, 2 * nc + 1);
  for (int i = 0; i < nc; ++i) {
    const auto& s = start[static_cast<std::size_t>(i)];
    const double w = 2 * std::numbers::pi * s.freq_hz, z = z0[static_cast<std::size_t>(i)];
    const double wd = w * std::sqrt(1 - z * z);
    for (int k = 0; k < m; ++k) {
      const double t = k / fs_hz, e = std::exp(-z * w * t);
      D(k, 2 * i) = e * std::cos(wd * t);
      D(k, 2 * i + 1) = e * std::sin(wd * t);
    }
  }
  D.col(2 * nc).setOnes();
  const Eigen::Map<const Eigen::VectorXd> yv(y.data(), m);
  return D.colPivHouseholderQr().solve(yv);
}

// Per component its harmonic number of component 0, or 0 when its frequency is free.
std::vector<int> harmonic_ties(const std::vector<PencilComponent>& start) {
  std::vector<int> tie(start.size(), 0);
  for (std::size_t i = 1; i < start.size(); ++i) tie[i] = std::max(0, start[i].harmonic);
  return tie;
}

// Parameters f_i, zeta_i, a_i, b_i per component, then the offset; a tied frequency is fixed
// (the residuals compute it from f0). Frequencies start at `start`'s (kept inside the bounds) and
// are bounded around `model`'s; dampings start at z0.
std::vector<ParamSpec> sinusoid_params(const std::vector<PencilComponent>& model,
                                       const std::vector<PencilComponent>& start, const std::vector<int>& tie,
                                       const std::vector<double>& z0, const Eigen::VectorXd& lin, double mean,
                                       double freq_rel_bound, double nyquist) {
  const int nc = static_cast<int>(model.size());
  std::vector<ParamSpec> params;
  for (int i = 0; i < nc; ++i) {
    const auto& s = model[static_cast<std::size_t>(i)];
    const double lo = (1 - freq_rel_bound) * s.freq_hz, hi = std::min((1 + freq_rel_bound) * s.freq_hz, nyquist);
    ParamSpec fp{fmt::format("f{}_hz", i), "Hz", std::clamp(start[static_cast<std::size_t>(i)].freq_hz, lo, hi), lo,
                 hi};
    if (tie[static_cast<std::size_t>(i)] > 0) {
      fp.start = tie[static_cast<std::size_t>(i)] * params.front().start;
      fp.lower = -std::numeric_limits<double>::infinity();
      fp.upper = std::numeric_limits<double>::infinity();
      fp.fixed = true;
    }
    params.push_back(fp);
    params.push_back({fmt::format("zeta{}", i), "1", z0[static_cast<std::size_t>(i)], kMinDampedZeta, max_zeta_of(s)});
    params.push_back({fmt::format("a{}", i), "", std::isfinite(lin(2 * i)) ? lin(2 * i) : 0.0});
    params.push_back({fmt::format("b{}", i), "", std::isfinite(lin(2 * i + 1)) ? lin(2 * i + 1) : 0.0});
  }
  params.push_back({"offset", "", std::isfinite(lin(2 * nc)) ? lin(2 * nc) : mean});
  return params;
}

// Residuals sum_i e^(-z w t) (a_i cos(wd t) + b_i sin(wd t)) + offset - y and their Jacobian.
ResidualJacobianFunction sinusoid_residuals(const std::vector<double>& y, const std::vector<int>& tie, double fs_hz,
                                            int np) {
  const int m = static_cast<int>(y.size());
  const int nc = static_cast<int>(tie.size());
  return [&y, &tie, fs_hz, nc, np, m](const double* p, double* r, double* J) {
    const double two_pi = 2 * std::numbers::pi;
    for (int k = 0; k < m; ++k) r[k] = p[np - 1] - y[static_cast<std::size_t>(k)];
    if (J)
      for (int k = 0; k < m; ++k) {
        double* row = J + static_cast<std::ptrdiff_t>(k) * np;
        std::fill(row, row + np, 0.0);
        row[np - 1] = 1.0;
      }
    for (int i = 0; i < nc; ++i) {
      const int k_tie = tie[static_cast<std::size_t>(i)];
      const double f = k_tie > 0 ? k_tie * p[0] : p[4 * i], z = p[4 * i + 1], a = p[4 * i + 2], b = p[4 * i + 3];
      const double w = two_pi * f, q = std::sqrt(1 - z * z), wd = w * q, sigma = z * w;
      // Rotations by recurrence: exp(-sigma dt), cos/sin(wd dt) per sample (exact enough over
      // a few thousand samples; renormalized every 256).
      const double dt = 1.0 / fs_hz;
      const double ed = std::exp(-sigma * dt), cd = std::cos(wd * dt), sd = std::sin(wd * dt);
      double E = 1, C = 1, S = 0;
      for (int k = 0; k < m; ++k) {
        const double t = k * dt;
        if ((k & 255) == 0) {
          E = std::exp(-sigma * t);
          C = std::cos(wd * t);
          S = std::sin(wd * t);
        }
        const double g = a * C + b * S, h = -a * S + b * C;
        r[k] += E * g;
        if (J) {
          double* row = J + static_cast<std::ptrdiff_t>(k) * np + 4 * i;
          const double dy_dw = E * t * (-z * g + q * h);
          const double dy_dz = E * t * (-w * g - (w * z / q) * h);
          if (k_tie > 0) J[static_cast<std::ptrdiff_t>(k) * np] += dy_dw * two_pi * k_tie;  // into f0's column
          else row[0] = dy_dw * two_pi;
          row[1] = dy_dz;
          row[2] = E * C;
          row[3] = E * S;
        }
        const double E2 = E * ed, C2 = C * cd - S * sd, S2 = S * cd + C * sd;
        E = E2;
        C = C2;
        S = S2;
      }
    }
    for (int k = 0; k < m; ++k)
      if (!std::isfinite(r[k])) return false;
    return true;
  };
}

// A tied frequency's estimate from f0's: k f0 with k times its error and interval.
void derive_tied_frequencies(FitResult& fit, const std::vector<int>& tie) {
  const auto& f0 = fit.param("f0_hz");
  for (std::size_t i = 1; i < tie.size(); ++i) {
    const int k_tie = tie[i];
    if (k_tie == 0) continue;
    for (auto& q : fit.params)
      if (q.name == fmt::format("f{}_hz", i)) {
        q.value = k_tie * f0.value;
        q.std_error = k_tie * f0.std_error;
        q.ci95_lo = k_tie * f0.ci95_lo;
        q.ci95_hi = k_tie * f0.ci95_hi;
        q.fixed = false;  // derived from f0's estimate, not held
        q.ci95_method = f0.ci95_method;
      }
  }
}

}  // namespace

namespace {

// `start`'s values with `model`'s ties and damping bounds, its frequencies inside model's bounds.
std::vector<PencilComponent> start_within(const std::vector<PencilComponent>& model,
                                          const std::vector<PencilComponent>& start, double freq_rel_bound,
                                          double nyquist) {
  if (start.size() != model.size())
    throw InputError(
        fmt::format("damped-sinusoid fit: a start set of {} components for a model of {}", start.size(), model.size()));
  std::vector<PencilComponent> st = model;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const double f = model[i].freq_hz;
    st[i].freq_hz = std::clamp(start[i].freq_hz, (1 - freq_rel_bound) * f, std::min((1 + freq_rel_bound) * f, nyquist));
    st[i].zeta = start[i].zeta;
  }
  return st;
}

// The fit of `model`'s components (frequency bounds, ties, damping bounds) from `start`'s values.
FitResult fit_from(const std::vector<double>& y, double fs_hz, const std::vector<PencilComponent>& model,
                   const std::vector<PencilComponent>& start, double freq_rel_bound) {
  if (!(freq_rel_bound > 0 && freq_rel_bound < 1))
    throw InputError("damped-sinusoid fit: the frequency bound must be in (0, 1)");
  const int m = static_cast<int>(y.size());
  const int nc = static_cast<int>(model.size());
  if (nc == 0) throw InputError("damped-sinusoid fit: no components to fit");
  if (m < 4 * nc + 10) throw InputError(fmt::format("damped-sinusoid fit: {} samples are too few", m));
  const double nyquist = fs_hz / 2;
  double mean = 0;
  for (double v : y) mean += v;
  mean /= m;

  const std::vector<PencilComponent> st = start_within(model, start, freq_rel_bound, nyquist);
  const std::vector<double> z0 = start_dampings(st);
  const Eigen::VectorXd lin = linear_start(y, fs_hz, st, z0);
  const std::vector<int> tie = harmonic_ties(model);
  LsqProblem prob;
  prob.params = sinusoid_params(model, st, tie, z0, lin, mean, freq_rel_bound, nyquist);
  const int np = static_cast<int>(prob.params.size());
  prob.num_residuals = m;
  prob.observed = y;
  prob.residuals_and_jacobian = sinusoid_residuals(y, tie, fs_hz, np);
  LsqOptions opt;
  opt.max_iterations = 200;
  opt.function_tolerance = 1e-12;
  opt.parameter_tolerance = 1e-12;
  opt.gradient_tolerance = 1e-14;
  FitResult fit = solve_least_squares("damped_sinusoids", prob, opt);
  derive_tied_frequencies(fit, tie);
  return fit;
}

}  // namespace

FitResult fit_damped_sinusoids(const std::vector<double>& y, double fs_hz, const std::vector<PencilComponent>& start,
                               double freq_rel_bound) {
  return fit_from(y, fs_hz, start, start, freq_rel_bound);
}

FitResult fit_damped_sinusoids_best_of(const std::vector<double>& y, double fs_hz,
                                       const std::vector<std::vector<PencilComponent>>& starts, double freq_rel_bound) {
  if (starts.empty()) throw InputError("damped-sinusoid fit: no start values");
  FitResult best;
  std::string first_failure;
  bool found = false;
  for (const auto& start : starts) {
    try {
      FitResult fit = fit_from(y, fs_hz, starts.front(), start, freq_rel_bound);
      // Strictly lower by more than rounding: starts that end in the same minimum keep the first.
      if (!found || fit.diagnostics.rss < best.diagnostics.rss * (1 - 1e-9)) best = std::move(fit);
      found = true;
    } catch (const FitError& e) {
      if (first_failure.empty()) first_failure = e.message();
    }
  }
  if (!found) throw FitError(first_failure);
  return best;
}

double damped_sinusoids_value(const FitResult& fit, double t) {
  double y = fit.value("offset");
  for (int i = 0;; ++i) {
    const std::string fi = fmt::format("f{}_hz", i);
    bool has = false;
    for (const auto& p : fit.params) has = has || p.name == fi;
    if (!has) break;
    const double w = 2 * std::numbers::pi * fit.value(fi), z = fit.value(fmt::format("zeta{}", i));
    const double wd = w * std::sqrt(1 - z * z);
    y += std::exp(-z * w * t) *
         (fit.value(fmt::format("a{}", i)) * std::cos(wd * t) + fit.value(fmt::format("b{}", i)) * std::sin(wd * t));
  }
  return y;
}

}  // namespace tunekit::fitting
