#include "tunekit/fitting/damped_sinusoids.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <limits>
#include <complex>
#include <numbers>
#include <optional>
#include <string>
#include <thread>

#include <Eigen/Core>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "lapack.hpp"

namespace tunekit::fitting {

namespace {

// The first `order` right singular vectors (as columns, L + 1 x order) of the Hankel matrix of y
// with L + 1 columns, largest singular value first (LAPACK's DGESVD).
Eigen::MatrixXd hankel_right_singular_vectors(const std::vector<double>& y, int L, int order) {
  int rows = static_cast<int>(y.size()) - L, cols = L + 1, k = std::min(rows, cols), one = 1, info = 0, lwork = -1;
  Eigen::MatrixXd Y(rows, cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) Y(r, c) = y[static_cast<std::size_t>(r + c)];
  Eigen::VectorXd sv(k);
  Eigen::MatrixXd vt(k, cols);
  double u_unused = 0, query = 0;
  dgesvd_("N", "S", &rows, &cols, Y.data(), &rows, sv.data(), &u_unused, &one, vt.data(), &k, &query, &lwork, &info, 1,
          1);
  lwork = std::max(1, static_cast<int>(query));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgesvd_("N", "S", &rows, &cols, Y.data(), &rows, sv.data(), &u_unused, &one, vt.data(), &k, work.data(), &lwork,
          &info, 1, 1);
  if (info != 0) throw FitError("matrix pencil: the singular value decomposition did not converge");
  return vt.topRows(order).transpose();
}

// The eigenvalues of the square matrix A (LAPACK's DGEEV).
std::vector<std::complex<double>> eigenvalues(Eigen::MatrixXd A) {
  int n = static_cast<int>(A.rows()), one = 1, info = 0, lwork = -1;
  std::vector<double> wr(static_cast<std::size_t>(n)), wi(static_cast<std::size_t>(n));
  double unused = 0, query = 0;
  dgeev_("N", "N", &n, A.data(), &n, wr.data(), wi.data(), &unused, &one, &unused, &one, &query, &lwork, &info, 1, 1);
  lwork = std::max(1, static_cast<int>(query));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgeev_("N", "N", &n, A.data(), &n, wr.data(), wi.data(), &unused, &one, &unused, &one, work.data(), &lwork, &info, 1,
         1);
  if (info != 0) throw FitError("matrix pencil: the eigenvalue problem did not converge");
  std::vector<std::complex<double>> z;
  for (std::size_t i = 0; i < wr.size(); ++i) z.emplace_back(wr[i], wi[i]);
  return z;
}

// The complex amplitudes h of y_k = sum_i h_i z_i^k in least squares, as the real problem of
// twice the size: [Re Z, -Im Z; Im Z, Re Z] [Re h; Im h] = [y; 0].
std::vector<std::complex<double>> vandermonde_amplitudes(const std::vector<double>& y,
                                                         const std::vector<std::complex<double>>& z) {
  const int n = static_cast<int>(y.size()), order = static_cast<int>(z.size());
  Eigen::MatrixXd Z(2 * n, 2 * order);
  for (int i = 0; i < order; ++i) {
    std::complex<double> p(1.0, 0.0);
    for (int k = 0; k < n; ++k) {
      Z(k, i) = Z(n + k, order + i) = p.real();
      Z(n + k, i) = p.imag();
      Z(k, order + i) = -p.imag();
      p *= z[static_cast<std::size_t>(i)];
    }
  }
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * n);
  for (int k = 0; k < n; ++k) rhs(k) = y[static_cast<std::size_t>(k)];
  const Eigen::VectorXd x = least_squares_solve(Z, rhs);
  std::vector<std::complex<double>> h;
  for (int i = 0; i < order; ++i) h.emplace_back(x(i), x(order + i));
  return h;
}

}  // namespace

std::vector<PencilComponent> matrix_pencil(const std::vector<double>& y, double fs_hz, int order, int pencil) {
  const int n = static_cast<int>(y.size());
  if (order < 1) throw InputError("matrix pencil: the order must be at least 1");
  int L = pencil > 0 ? pencil : std::min(n / 3, 100);
  L = std::max(L, order + 1);
  if (n < 2 * L + 1 || !(fs_hz > 0))
    throw InputError(fmt::format("matrix pencil: {} samples are too few for {} exponentials", n, order));
  // The Hankel data matrix's dominant right singular vectors V span the signal; the poles z are
  // the eigenvalues of pinv(V1) V2 (V1: V's rows 0..L-1, V2: rows 1..L), each column of it the
  // least-squares solution of V1 a = V2's column.
  const Eigen::MatrixXd V = hankel_right_singular_vectors(y, L, order);
  const Eigen::MatrixXd V1 = V.topRows(L), V2 = V.bottomRows(L);
  Eigen::MatrixXd A(order, order);
  for (int c = 0; c < order; ++c) A.col(c) = least_squares_solve(V1, V2.col(c));
  const auto z = eigenvalues(A);
  const auto h = vandermonde_amplitudes(y, z);

  std::vector<PencilComponent> out;
  for (std::size_t i = 0; i < z.size(); ++i) {
    const double wd = std::arg(z[i]) * fs_hz;  // rad/s
    if (!(wd > 0)) continue;                   // conjugate twin or a real (non-oscillating) pole
    const double sigma = -std::log(std::abs(z[i])) * fs_hz;
    const double wn = std::hypot(wd, sigma);
    PencilComponent c;
    c.freq_hz = wn / (2 * std::numbers::pi);
    c.zeta = sigma / wn;
    c.amplitude = 2 * std::abs(h[i]);
    c.phase_rad = std::arg(h[i]);
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
  return least_squares_solve(D, Eigen::Map<const Eigen::VectorXd>(y.data(), m));
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

namespace {

// One start's fit, or the message of the FitError it ended in.
struct StartOutcome {
  std::optional<FitResult> fit;
  std::string failure;
};

// Every start's fit, the odd-numbered ones on a second thread where the machine has two cores.
// Each fit is computed exactly as on one thread, and the caller reads them in order.
std::vector<StartOutcome> fit_every_start(const std::vector<double>& y, double fs_hz,
                                          const std::vector<std::vector<PencilComponent>>& starts,
                                          double freq_rel_bound) {
  std::vector<StartOutcome> out(starts.size());
  auto fit_each = [&](std::size_t first, std::size_t stride) {
    for (std::size_t i = first; i < starts.size(); i += stride) try {
        out[i].fit = fit_from(y, fs_hz, starts.front(), starts[i], freq_rel_bound);
      } catch (const FitError& e) {
        out[i].failure = e.message();
      }
  };
  if (starts.size() < 2 || std::thread::hardware_concurrency() < 2) {
    fit_each(0, 1);
    return out;
  }
  auto odd = std::async(std::launch::async, fit_each, 1, 2);
  fit_each(0, 2);
  odd.get();
  return out;
}

}  // namespace

FitResult fit_damped_sinusoids_best_of(const std::vector<double>& y, double fs_hz,
                                       const std::vector<std::vector<PencilComponent>>& starts, double freq_rel_bound) {
  if (starts.empty()) throw InputError("damped-sinusoid fit: no start values");
  std::vector<StartOutcome> outcomes = fit_every_start(y, fs_hz, starts, freq_rel_bound);
  FitResult* best = nullptr;
  std::string first_failure;
  for (auto& o : outcomes) {
    if (!o.fit) {
      if (first_failure.empty()) first_failure = o.failure;
      continue;
    }
    // Strictly lower by more than rounding: starts that end in the same minimum keep the first.
    if (best == nullptr || o.fit->diagnostics.rss < best->diagnostics.rss * (1 - 1e-9)) best = &*o.fit;
  }
  if (best == nullptr) throw FitError(first_failure);
  return std::move(*best);
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
