#include "tunekit/fitting/first_order.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <array>
#include <cstdio>
#include <cstring>
#include <memory>
#include <span>

#include <Eigen/Dense>
#include <ceres/ceres.h>
#include <fmt/format.h>

#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/stats.hpp"

#include "tunekit/core/error.hpp"
#include "first_order_detail.hpp"
#include "tunekit/fitting/levenberg_marquardt.hpp"
#include "number_text.hpp"
#include "solver_logging.hpp"

namespace tunekit::fitting {
namespace first_order_detail {

namespace {

// Whether every t and y is finite and t increases: one pass without a branch per sample, four
// samples at a time (x - x is 0 for a finite x only). Built for AVX2 beside the baseline.
[[gnu::target_clones("avx2", "default")]] bool samples_in_order(const double* t, const double* y, std::size_t n) {
  using Lanes = double __attribute__((vector_size(32)));
  auto load = [](Lanes& v, const double* x) { std::memcpy(&v, x, sizeof v); };
  Lanes a, b, c;
  auto ok = Lanes{} == Lanes{};  // every lane true
  std::size_t i = 1;
  for (; i + 4 <= n; i += 4) {
    load(a, t + i);
    load(b, t + i - 1);
    load(c, y + i);
    ok &= (a > b) & (a - a == 0) & (c - c == 0);
  }
  bool good = ok[0] && ok[1] && ok[2] && ok[3] && n > 0 && std::isfinite(t[0]) && std::isfinite(y[0]);
  for (; i < n; ++i) good = good && t[i] > t[i - 1] && std::isfinite(t[i]) && std::isfinite(y[i]);
  return good;
}

}  // namespace

void check_record(const StepRecord& r, const std::string& what) {
  if (r.t.size() != r.y.size()) throw InputError(what + ": time and output have different lengths");
  if (r.t.size() < 5)
    throw InputError(what + ": too few samples (" + std::to_string(r.t.size()) +
                     ") to fit a step response; at least 5 are needed");
  // The samples one at a time only to name the first bad one.
  const bool in_order = samples_in_order(r.t.data(), r.y.data(), r.t.size());
  for (std::size_t i = 0; !in_order && i < r.t.size(); ++i) {
    if (!std::isfinite(r.t[i]) || !std::isfinite(r.y[i])) throw InputError(what + ": NaN or infinite sample");
    if (i > 0 && !(r.t[i] > r.t[i - 1]))
      throw InputError(what + ": time is not increasing at sample " + std::to_string(i + 1) +
                       " (t = " + text::g4(r.t[i]) + " s)");
  }
  if (!(std::abs(r.du) > 0) || !std::isfinite(r.du)) throw InputError(what + ": the input step size is zero");
  if (!r.u.empty() && r.u.size() != r.t.size()) throw InputError(what + ": time and input have different lengths");
  for (double v : r.u)
    if (!std::isfinite(v)) throw InputError(what + ": NaN or infinite input sample");
  if (r.input_t.size() != r.input_u.size())
    throw InputError(what + ": the input track has different numbers of instants and values");
  for (std::size_t i = 0; i < r.input_t.size(); ++i)
    if (!std::isfinite(r.input_t[i]) || !std::isfinite(r.input_u[i]) || (i > 0 && r.input_t[i] < r.input_t[i - 1]))
      throw InputError(what + ": the input track's instants decrease or it holds NaN or infinity");
  // The output is constant when no sample differs from the first (the samples are finite here;
  // a noisy record differs at its second sample).
  if (std::all_of(r.y.begin(), r.y.end(), [y0 = r.y[0]](double v) { return v == y0; }))
    throw InputError(what + ": the output is constant; there is no response to fit");
  // The times increase here: the samples after the step are those past the first later than it.
  const auto after = static_cast<std::size_t>(r.t.end() - std::upper_bound(r.t.begin(), r.t.end(), r.t_step));
  if (after < 4)
    throw InputError(what + ": only " + std::to_string(after) + " samples after the step at t = " + text::g4(r.t_step) +
                     " s; at least 4 are needed");
}

double mean_of(const std::vector<double>& v, std::size_t b, std::size_t e) {
  if (e <= b) return 0;
  return std::accumulate(v.begin() + static_cast<std::ptrdiff_t>(b), v.begin() + static_cast<std::ptrdiff_t>(e), 0.0) /
         static_cast<double>(e - b);
}

// Residuals model - y and the Jacobian for one record; p = {K, tau, theta, y0}; columns of the
// Jacobian row are placed at cols[0..3] of a row of width `width`.
/// The step model at sample i of one record and its derivatives by K, tau and theta (by y0: 1).
StepModelPoint step_model_at(const StepRecord& r, std::size_t i, double K, double tau, double theta, double y0) {
  const double s = r.t[i] - r.t_step - theta;
  if (s <= 0) return {y0, 0, 0, 0};
  const double e = std::exp(-s / tau);
  return {y0 + K * r.du * (1 - e), r.du * (1 - e), -K * r.du * e * s / (tau * tau), -K * r.du * e / tau};
}

namespace {

// The input a record's response starts settled at: the mean recorded input before the step (the
// first value when the record starts at the step).
double settled_input(const StepRecord& r) {
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < r.t.size() && r.t[i] < r.t_step; ++i, ++n) sum += r.u[i];
  return n > 0 ? sum / static_cast<double>(n) : r.u.front();
}

// Where (s) the window in which r.u[k] holds begins (StepRecord::u_hold); the last window ends
// one sample interval (from_stamp) or half of one (centred) after its stamp.
double window_begin(const StepRecord& r, std::size_t k) {
  const std::size_t n = r.t.size();
  if (n < 2) return r.t[0];
  const bool centred = r.u_hold == InputHold::centred;
  if (k == n) return r.t[n - 1] + (centred ? 0.5 : 1.0) * (r.t[n - 1] - r.t[n - 2]);
  if (!centred) return r.t[k];
  if (k == 0) return r.t[0] - 0.5 * (r.t[1] - r.t[0]);
  return 0.5 * (r.t[k - 1] + r.t[k]);
}

// The input the driven model follows: the ideal step from u_before to u_after at t_step, which
// places the change within its window where the record's instant says, plus each window's
// departure from that step's mean over the window (a pause, a ramp, a level a little off), held
// over the window. A record of an ideal step has no departures and gives the ideal step's model.
struct DrivenInput {
  double u_before, u_after;
  std::vector<double> departure;  // per window
};

DrivenInput driven_input(const StepRecord& r) {
  DrivenInput in;
  in.u_before = settled_input(r);
  in.u_after = in.u_before + r.du;
  const std::size_t n = r.t.size();
  in.departure.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double b = window_begin(r, k), e = window_begin(r, k + 1);
    const double before = std::clamp((r.t_step - b) / (e - b), 0.0, 1.0);  // share of the window before the step
    in.departure[k] = r.u[k] - (before * in.u_before + (1 - before) * in.u_after);
  }
  return in;
}

// A departure this small against the step is rounding in the log, not feed.
constexpr double kNegligibleDeparture = 1e-9;

// The first-order response x to that input, dx/dt = (u(t - theta) - x) / tau, exact for an input
// constant between the window boundaries and the step: across a stretch d of constant input v,
// x <- v + (x - v) e and its sensitivity w = dx/dtau <- w e + (x - v) e d / tau^2, e = exp(-d / tau).
// The samples are taken at s = t - theta in the input's time, so dx/dtheta = -(v - x) / tau.
void driven_model_points(const StepRecord& r, double K, double tau, double theta, double y0,
                         std::vector<StepModelPoint>& out) {
  if (!r.input_t.empty()) return track_model_points(r, K, tau, theta, y0, out);
  const std::size_t n = r.t.size();
  out.resize(n);
  const DrivenInput in = driven_input(r);
  const double x0 = in.u_before;
  double x = x0, w = 0, s_cur = 0, ideal = in.u_before, dep = 0;
  bool started = false, stepped = false;  // until the first event, x rests at x0
  auto advance = [&](double s_new) {
    const double d = s_new - s_cur, v = ideal + dep;
    if (started && d > 0) {
      const double e = std::exp(-d / tau);
      w = w * e + (x - v) * e * d / (tau * tau);
      x = v + (x - v) * e;
    }
    if (!started || d > 0) s_cur = s_new;
    started = true;
  };
  std::size_t next = 0;  // the next window to begin
  for (std::size_t i = 0; i < n; ++i) {
    const double s = r.t[i] - theta;
    for (;;) {
      const double b = next < n ? window_begin(r, next) : std::numeric_limits<double>::infinity();
      const double at = std::min(b, stepped ? std::numeric_limits<double>::infinity() : r.t_step);
      if (!(at <= s)) break;
      if (!stepped && r.t_step <= b) {
        advance(at);
        ideal = in.u_after;
        stepped = true;
      } else if (const double d = in.departure[next++]; d != dep) {
        advance(at);  // a window that holds the input as it is needs no stop
        dep = d;
      }
    }
    advance(s);
    out[i] = {y0 + K * (x - x0), x - x0, K * w, -K * (ideal + dep - x) / tau};
  }
}

}  // namespace

bool input_is_ideal_step(const StepRecord& r) {
  if (!r.input_t.empty() || r.u.empty() || r.u.size() != r.t.size()) return false;
  const DrivenInput in = driven_input(r);
  const double negligible = kNegligibleDeparture * std::max(std::abs(r.du), std::abs(in.u_before));
  return std::all_of(in.departure.begin(), in.departure.end(),
                     [negligible](double d) { return std::abs(d) <= negligible; });
}

void step_model_points(const StepRecord& r, double K, double tau, double theta, double y0,
                       std::vector<StepModelPoint>& out) {
  if (follows_input(r)) return driven_model_points(r, K, tau, theta, y0, out);
  out.resize(r.t.size());
  for (std::size_t i = 0; i < r.t.size(); ++i) out[i] = step_model_at(r, i, K, tau, theta, y0);
}

void step_residuals(const StepRecord& r, double K, double tau, double theta, double y0, double* res, double* jac,
                    std::size_t width, const std::size_t cols[4]) {
  const std::size_t n = r.t.size();
  if (follows_input(r)) {
    std::vector<StepModelPoint> pts;
    driven_model_points(r, K, tau, theta, y0, pts);
    for (std::size_t i = 0; i < n; ++i) {
      res[i] = pts[i].m - r.y[i];
      if (jac == nullptr) continue;
      double* row = jac + i * width;
      row[cols[0]] = pts[i].dK;
      row[cols[1]] = pts[i].dtau;
      row[cols[2]] = pts[i].dtheta;
      row[cols[3]] = 1.0;
    }
    return;
  }
  if (jac == nullptr) {  // the residuals alone: the model value of step_model_at, no derivatives
    for (std::size_t i = 0; i < n; ++i) {
      const double s = r.t[i] - r.t_step - theta;
      res[i] = (s <= 0 ? y0 : y0 + K * r.du * (1 - std::exp(-s / tau))) - r.y[i];
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const StepModelPoint p = step_model_at(r, i, K, tau, theta, y0);
    res[i] = p.m - r.y[i];
    if (jac != nullptr) {
      double* row = jac + i * width;
      row[cols[0]] = p.dK;
      row[cols[1]] = p.dtau;
      row[cols[2]] = p.dtheta;
      row[cols[3]] = 1.0;
    }
  }
}

// Ordinary least-squares line z = a + b t; returns {a, b, r2}.
std::array<double, 3> line_fit(const std::vector<double>& t, const std::vector<double>& z) {
  const double n = static_cast<double>(t.size());
  const double mt = std::accumulate(t.begin(), t.end(), 0.0) / n;
  const double mz = std::accumulate(z.begin(), z.end(), 0.0) / n;
  double stt = 0, stz = 0, szz = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    stt += (t[i] - mt) * (t[i] - mt);
    stz += (t[i] - mt) * (z[i] - mz);
    szz += (z[i] - mz) * (z[i] - mz);
  }
  if (stt <= 0) return {mz, 0, 0};
  const double b = stz / stt;
  const double r2 = szz > 0 ? (stz * stz) / (stt * szz) : 0;
  return {mz - b * mt, b, r2};
}

namespace {

// Samples per block of normal_equations: one exponential per block on a regular clock (BlockDecay).
constexpr std::size_t kBlock = 256;

// exp(-(t_k - t_on) / tau) for the samples of a block, without an exponential per sample on a
// regular clock: e_k = e_b exp(-j h / tau) exp(-delta / tau), b the block's first sample, j = k - b,
// h the record's mean sample interval after t_on, delta = t_k - t_b - j h. e_b is the exponential
// of the sample itself, exp(-j h / tau) a table of the block's length per evaluation, and on a
// regular clock delta is rounding, so that exp(-delta / tau) is 1 - x + x^2 / 2 (x = delta / tau,
// at most 1e-6: the series' remainder is below 2e-19). A jittery or gappy clock's samples, whose
// delta is larger, take their exponential as it is. Each value is within a few rounding units of
// exp(-(t_k - t_on) / tau), whose argument carries the rounding of t_k - t_on already.
struct BlockDecay {
  static constexpr double kSeriesMax2 = 1e-12;  // the largest x^2 of the series
  BlockDecay(const std::vector<double>& times, std::size_t first, double start, double inverse_tau)
      : t(times), t_on(start), inv_tau(inverse_tau) {
    const std::size_t n = t.size();
    if (n - first < 2) return;
    h = (t[n - 1] - t[first]) / static_cast<double>(n - 1 - first);
    const std::size_t len = std::min(kBlock, n - first);
    for (std::size_t j = 0; j < len; ++j) ratio[j] = std::exp(-(static_cast<double>(j) * h) * inv_tau);
  }
  /// e_b of the block that starts at sample b.
  double base(std::size_t b) const { return std::exp(-(t[b] - t_on) * inv_tau); }
  /// e_k of the block that starts at sample b, whose e_b is eb.
  double at(std::size_t b, double eb, std::size_t k) const {
    const std::size_t j = k - b;
    const double x = ((t[k] - t[b]) - static_cast<double>(j) * h) * inv_tau;
    return x * x <= kSeriesMax2 ? eb * ratio[j] * (1 - x * (1 - 0.5 * x)) : std::exp(-(t[k] - t_on) * inv_tau);
  }
  const std::vector<double>& t;
  double t_on, inv_tau, h = 0;
  std::array<double, kBlock> ratio{};
};

// normal_equations for a record driven by its recorded input: the rows of driven_model_points.
double driven_normal_equations(const StepRecord& r, const double p[4], Eigen::Matrix4d& JtJ, Eigen::Vector4d& Jtr,
                               std::span<double> res_out) {
  std::vector<StepModelPoint> pts;
  driven_model_points(r, p[0], p[1], p[2], p[3], pts);
  JtJ.setZero();
  Jtr.setZero();
  double rss = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector4d j(pts[i].dK, pts[i].dtau, pts[i].dtheta, 1.0);
    const double res = pts[i].m - r.y[i];
    if (!res_out.empty()) res_out[i] = res;
    rss += res * res;
    JtJ.selfadjointView<Eigen::Upper>().rankUpdate(j);
    Jtr += j * res;
  }
  JtJ.triangularView<Eigen::StrictlyLower>() = JtJ.transpose();
  return rss;
}
}  // namespace

namespace {

// Four samples to a register: each lane sums every fourth sample.
using Lanes = double __attribute__((vector_size(32)));

// The sums over the samples after the response's start that the normal equations of an ideal
// step are made of, per sample: its decay e = exp(-s / tau) (s the time since the start), f = 1 - e,
// es = e s and the residual r. The Jacobian's row is (du f, c1 es, c2 e, 1), c2 = -K du / tau,
// c1 = c2 / tau, so J'J and J'r are these sums times constants (step_equations).
struct DecaySums {
  Lanes ff{}, fe{}, fes{}, eses{}, ese{}, ee{}, f{}, es{}, e{}, fr{}, esr{}, er{}, rr{}, r{};
};

// Adds the samples [b, e) of one block (at most kBlock, after the response's start) to `a`, their
// decays from dec (BlockDecay::at, four at a time); the residuals y0 + K (du f) - y (rounded as
// the model's value is) into res_out[b .. e) unless it is null. Built for AVX2 as well as the
// baseline: then four samples take one instruction.
[[gnu::target_clones("avx2", "default")]] void add_decay_sums(const BlockDecay& dec, const double* y, std::size_t b,
                                                              std::size_t e, const double p[4], double du,
                                                              double* res_out, DecaySums& a) {
  const double K = p[0], y0 = p[3], t_on = dec.t_on, tb = dec.t[b], eb = dec.base(b);
  const double* t = dec.t.data();
  Lanes ff = a.ff, fe = a.fe, fes = a.fes, eses = a.eses, ese = a.ese, ee = a.ee, fs = a.f, ess = a.es, esum = a.e;
  Lanes fr = a.fr, esr = a.esr, er = a.er, rr = a.rr, rs = a.r;
  Lanes jv = {0, 1, 2, 3};
  const std::size_t len = e - b;
  for (std::size_t g = 0; g < len; g += 4, jv += 4) {
    Lanes tv, yv, ev, on = {1, 1, 1, 1};
    if (g + 4 <= len) {
      Lanes rt;
      __builtin_memcpy(&tv, t + b + g, sizeof tv);
      __builtin_memcpy(&yv, y + b + g, sizeof yv);
      __builtin_memcpy(&rt, dec.ratio.data() + g, sizeof rt);
      const Lanes x = ((tv - tb) - jv * dec.h) * dec.inv_tau;
      ev = eb * rt * (1 - x * (1 - 0.5 * x));
      const auto off = x * x > BlockDecay::kSeriesMax2;  // off the series: a jittery clock
      for (std::size_t l = 0; l < 4; ++l)
        if (off[l]) ev[l] = dec.at(b, eb, b + g + l);
    } else {  // the block's last samples: the lanes past its end add nothing
      for (std::size_t l = 0; l < 4; ++l) {
        const std::size_t k = b + g + l;
        const bool in = g + l < len;
        tv[l] = in ? t[k] : t_on, yv[l] = in ? y[k] : y0, ev[l] = in ? dec.at(b, eb, k) : 1, on[l] = in ? 1 : 0;
      }
    }
    const Lanes f = (1 - ev) * on, es = ev * (tv - t_on) * on, res = y0 + K * (du * f) - yv;
    ev *= on;
    if (res_out != nullptr)
      for (std::size_t l = 0; l < 4 && g + l < len; ++l) res_out[b + g + l] = res[l];
    ff += f * f, fe += f * ev, fes += f * es, eses += es * es, ese += es * ev, ee += ev * ev;
    fs += f, ess += es, esum += ev;
    fr += f * res, esr += es * res, er += ev * res, rr += res * res, rs += res;
  }
  a = {ff, fe, fes, eses, ese, ee, fs, ess, esum, fr, esr, er, rr, rs};
}

double lanes_sum(const Lanes& v) { return (v[0] + v[1]) + (v[2] + v[3]); }

// J'J and J'r of an ideal step from its sums after the response's start, the samples before it
// (n_pre, the sum of their residuals r_pre and of their squares rss_pre) and the constants of the
// Jacobian's row; returns the residual sum of squares.
double step_equations(const DecaySums& a, double n_after, double n_pre, double r_pre, double rss_pre, double du,
                      double c1, double c2, Eigen::Matrix4d& JtJ, Eigen::Vector4d& Jtr) {
  const double ff = lanes_sum(a.ff), fe = lanes_sum(a.fe), fes = lanes_sum(a.fes), eses = lanes_sum(a.eses);
  const double ese = lanes_sum(a.ese), ee = lanes_sum(a.ee), f = lanes_sum(a.f), es = lanes_sum(a.es);
  const double e = lanes_sum(a.e);
  JtJ << du * du * ff, du * c1 * fes, du * c2 * fe, du * f,   //
      du * c1 * fes, c1 * c1 * eses, c1 * c2 * ese, c1 * es,  //
      du * c2 * fe, c1 * c2 * ese, c2 * c2 * ee, c2 * e,      //
      du * f, c1 * es, c2 * e, n_after + n_pre;
  Jtr << du * lanes_sum(a.fr), c1 * lanes_sum(a.esr), c2 * lanes_sum(a.er), lanes_sum(a.r) + r_pre;
  return lanes_sum(a.rr) + rss_pre;
}

}  // namespace

// Accumulates J^T J (4x4), J^T r and the residual sum of squares for one record without storing
// the Jacobian (100k samples cost a millisecond or two).
double normal_equations(const StepRecord& r, const double p[4], Eigen::Matrix4d& JtJ, Eigen::Vector4d& Jtr,
                        std::span<double> res_out) {
  if (follows_input(r)) return driven_normal_equations(r, p, JtJ, Jtr, res_out);
  // Before the response starts (the times increase, so these are the first samples) the Jacobian
  // row is (0, 0, 0, 1): only the count and the sum of residuals matter there. Afterwards the
  // products of the decays the Jacobian's row is made of are summed four samples to a register
  // (add_decay_sums), a block of samples at a time (BlockDecay: a table and one exponential per
  // block on a regular clock).
  const std::size_t n = r.t.size();
  const double tau = p[1], theta = p[2], y0 = p[3], du = r.du;
  const double inv_tau = 1.0 / tau;
  const double t_on = r.t_step + theta;
  const bool keep = !res_out.empty();
  double rss = 0, n_pre = 0, r_sum = 0;
  std::size_t i = 0;
  for (; i < n && !(r.t[i] - t_on > 0); ++i) {
    const double res = y0 - r.y[i];
    if (keep) res_out[i] = res;
    rss += res * res;
    n_pre += 1;
    r_sum += res;
  }
  DecaySums sums;
  const BlockDecay decay(r.t, i, t_on, inv_tau);
  for (std::size_t begin = i; begin < n; begin += kBlock)
    add_decay_sums(decay, r.y.data(), begin, std::min(n, begin + kBlock), p, du, keep ? res_out.data() : nullptr, sums);
  const double c2 = -(p[0] * du) * inv_tau;
  return step_equations(sums, static_cast<double>(n - i), n_pre, r_sum, rss, du, c2 * inv_tau, c2, JtJ, Jtr);
}

// Levenberg-Marquardt on the 4x4 normal equations, carried to convergence by Ceres Solver's own
// tests (lm_detail::confirm) with the tolerances the Ceres solve of the same problem would use.
// One solver instead of a polish followed by a Ceres solve that only confirmed it: that solve
// evaluated and factored the 100k x 4 Jacobian for an iteration that did not move the parameters.
// The residuals are not kept while it iterates (normal_solve_result evaluates them once at the
// end point): two buffers of the record's length, written on every evaluation, cost more.
struct NormalSolve {
  lm_detail::Confirmed confirmed;
  int iterations = 0;   // iterations after the polish
  Eigen::Matrix4d JtJ;  // J'J at the end point (unpinned)
  double rss = 0;       // residual sum of squares there
};

NormalSolve solve_normal_equations(const StepRecord& r, double p[4], const double lo[4], const double hi[4],
                                   const bool fixed[4], const lm_detail::Tolerances& tol) {
  auto equations = [&r](std::span<const double> q, Eigen::Matrix4d& JtJ, Eigen::Vector4d& Jtr) {
    return normal_equations(r, q.data(), JtJ, Jtr);
  };
  const std::span<double> ps(p, 4);
  const std::span<const double> los(lo, 4), his(hi, 4);
  lm_detail::Equations<Eigen::Matrix4d, Eigen::Vector4d> at;
  at.cost = equations(std::span<const double>(ps), at.N, at.g);
  double lambda = lm_detail::kInitialDamping;
  // The polish stops at a relative decrease of 1e-8 (kStopRelativeDecrease); confirm continues
  // from there with the same damping, as the Ceres solve after the polish did. Both hold a
  // parameter at a bound it is pressed against (theta_s at 0 for a response without dead time).
  lm_detail::polish_from(ps, los, his, fixed, equations, at, lambda, true);
  NormalSolve s;
  s.confirmed = lm_detail::confirm(ps, los, his, fixed, equations, at, lambda, tol);
  s.iterations = s.confirmed.iterations;
  // The cost has a kink wherever the response's start t_step + theta_s crosses a sample: the
  // derivative by theta_s jumps there. An optimum on a kink makes the steps across it fail,
  // the damping grows, and the iteration stops on steps too small to finish K, tau_s and y0.
  // With theta_s held where it is, the rest is smooth: finish them from the undamped start.
  if (s.confirmed.converged() && s.confirmed.rejected_trials > 0 && !fixed[2]) {
    const bool theta_held[4] = {fixed[0], fixed[1], true, fixed[3]};
    s.iterations +=
        lm_detail::confirm(ps, los, his, theta_held, equations, at, lm_detail::kInitialDamping, tol).iterations;
  }
  s.JtJ = at.N;
  s.rss = at.cost;
  return s;
}

const char* end_name(lm_detail::ConfirmEnd e) {
  switch (e) {
    case lm_detail::ConfirmEnd::function_tolerance: return "function tolerance";
    case lm_detail::ConfirmEnd::parameter_tolerance: return "parameter tolerance";
    case lm_detail::ConfirmEnd::gradient_tolerance: return "gradient tolerance";
    case lm_detail::ConfirmEnd::no_decrease: return "no decrease";
    case lm_detail::ConfirmEnd::iteration_limit: return "iteration limit";
  }
  return "";
}

// The FitResult of a converged solve_normal_equations: what solve_least_squares reports for the
// same solution (residual diagnostics, bound warnings), without the covariance. `scratch` (one
// element per sample) holds the residuals for the diagnostics and is overwritten.
FitResult normal_solve_result(const StepRecord& r, StepModel model, const std::vector<ParamSpec>& specs,
                              const double p[4], const NormalSolve& s, std::span<double> scratch) {
  FitResult f;
  f.model = model_name(model);
  f.diagnostics.iterations = s.iterations;
  f.diagnostics.solver = fmt::format(
      "Levenberg-Marquardt on the 4x4 normal equations, polished start: {} further iterations, final residual sum "
      "of squares {:.6e}, converged ({})",
      s.iterations, s.rss, end_name(s.confirmed.end));
  for (const auto& ps : specs)
    if (!ps.fixed) ++f.diagnostics.num_parameters;
  f.diagnostics.converged = true;
  for (int j = 0; j < 4; ++j)
    if (!std::isfinite(p[j])) throw FitError(f.model + ": the solution is not finite (" + f.diagnostics.solver + ")");
  // The residuals at p for the diagnostics: one more evaluation, the arithmetic of the solver's
  // evaluation at p (the same residuals to the bit). Their whiteness test overwrites them.
  Eigen::Matrix4d JtJ;
  Eigen::Vector4d Jtr;
  normal_equations(r, p, JtJ, Jtr, scratch);
  fill_residual_diagnostics_in_place(f, scratch, r.y, true);
  for (std::size_t j = 0; j < 4; ++j) {
    const auto& ps = specs[j];
    Param prm;
    prm.name = ps.name;
    prm.unit = ps.unit;
    prm.value = p[j];
    prm.fixed = ps.fixed;
    if (!ps.fixed && (p[j] <= ps.lower || p[j] >= ps.upper))
      f.warnings.push_back(ps.name + " ended on its bound (" + std::to_string(p[j]) + ")");
    f.params.push_back(prm);
  }
  return f;
}

// Standard errors and 95 % intervals from the 4x4 normal matrix at the solution: the same
// s^2 (J^T J)^-1 that ceres::Covariance computes from J, with the same rank check (ratio of
// the extreme singular values of J, i.e. the square root of that of J^T J). `at_solution`: J^T J
// at f's parameters when the solver has it, otherwise it is computed here. `scratch`: a buffer of
// one element per sample that may be overwritten, or empty.
void fill_covariance(FitResult& f, const StepRecord& r, const LsqOptions& o, const Eigen::Matrix4d* at_solution,
                     std::span<double> scratch = {}) {
  Eigen::Matrix4d JtJ;
  if (at_solution != nullptr) {
    JtJ = *at_solution;
  } else {
    const double p[4] = {f.value("K"), f.value("tau_s"), f.value("theta_s"), f.value("y0")};
    Eigen::Vector4d Jtr;
    normal_equations(r, p, JtJ, Jtr);
  }
  std::vector<int> free_idx;
  for (int j = 0; j < 4; ++j)
    if (!f.params[static_cast<std::size_t>(j)].fixed) free_idx.push_back(j);
  const int k = static_cast<int>(free_idx.size());
  // Fixed parameters get an identity row and column; scaled to unit diagonal so that the
  // condition number reflects identifiability, not units (a correlation-like matrix: its
  // eigenvalue range always contains the 1 of the padding).
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  for (int j : free_idx)
    for (int i : free_idx) M(j, i) = JtJ(j, i);
  Eigen::Vector4d d;
  for (int j = 0; j < 4; ++j) d(j) = 1.0 / std::sqrt(std::max(M(j, j), 1e-300));
  const Eigen::Matrix4d S = d.asDiagonal() * M * d.asDiagonal();
  const Eigen::VectorXd eigenvalues = symmetric_eigenvalues(S);  // once per fit: the solver compiled once
  const double lmin = eigenvalues.minCoeff(), lmax = eigenvalues.maxCoeff();
  std::string names;
  for (int j : free_idx) names += (names.empty() ? "" : ", ") + f.params[static_cast<std::size_t>(j)].name;
  if (!(lmax > 0) || !(lmin > 0) || std::sqrt(lmin / lmax) < std::max(o.min_reciprocal_condition, 1e-10))
    throw FitError(f.model + ": parameters not identifiable from these data (the Jacobian of " + names +
                   " is rank deficient); record a longer or richer response, or fix a parameter");
  const Eigen::Matrix4d Sinv = S.inverse();
  const int dof = f.diagnostics.num_observations - k;
  if (dof <= 0) throw FitError(f.model + ": as many parameters as data points; no uncertainty can be estimated");
  const double s2 = o.absolute_sigma ? 1.0 : f.diagnostics.rss / dof;
  const double tq = t_multiplier(o.confidence, dof);
  // The step instant is known to one sample: its rectangular uncertainty joins the dead time's
  // (see step_instant_resolution).
  const double theta_resolution = step_instant_resolution(r, scratch);
  for (int j : free_idx) {
    auto& prm = f.params[static_cast<std::size_t>(j)];
    prm.std_error = std::sqrt(Sinv(j, j) * d(j) * d(j) * s2 + (j == 2 ? theta_resolution * theta_resolution : 0.0));
    prm.ci95_lo = prm.value - tq * prm.std_error;
    prm.ci95_hi = prm.value + tq * prm.std_error;
    if (!std::isfinite(prm.std_error))
      throw FitError(f.model + ": the uncertainty of " + prm.name + " is not finite; it is not identifiable");
  }
}
void check_identifiable(const FitResult& f, const StepRecord* rec, double duration, bool have_stderr) {
  const auto& tau = f.param("tau_s");
  if (tau.value >= kTauMaxFactor * duration * 0.999 || (have_stderr && !(tau.std_error < tau.value)))
    throw FitError(f.model + ": tau_s is not identifiable from this record (tau_s = " + text::g4(tau.value) + " s +- " +
                   text::g4(tau.std_error) + " s against " + text::g4(duration) + " s of response" +
                   (rec != nullptr ? " after the step at t = " + text::g4(rec->t_step) + " s" : std::string()) +
                   "); the step is too short to see the time constant: record longer after the step");
  const auto& theta = f.param("theta_s");
  if (!theta.fixed && theta.value >= 0.9 * duration * 0.999)
    throw FitError(f.model + ": theta_s ran to its bound (" + text::g4(theta.value) +
                   " s): no response to the step is visible");
}

double response_duration(const StepRecord& r) { return r.t.back() - r.t_step; }

double step_instant_resolution(const StepRecord& r, std::span<double> scratch) {
  return r.t.size() < 2 ? 0 : median_interval(r.t, scratch) / std::sqrt(12.0);
}

}  // namespace first_order_detail

using namespace first_order_detail;

std::string model_name(StepModel m) { return m == StepModel::fo ? "first_order" : "fopdt"; }

bool logged_input_is_ideal_step(const StepRecord& r) { return input_is_ideal_step(r); }

std::vector<double> step_model_output(const StepRecord& r, double K, double tau_s, double theta_s, double y0) {
  std::vector<StepModelPoint> pts;
  step_model_points(r, K, tau_s, theta_s, y0, pts);
  std::vector<double> out(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) out[i] = pts[i].m;
  return out;
}

double step_response(double t, double t_step, double du, double K, double tau_s, double theta_s, double y0) {
  const double s = t - t_step - theta_s;
  return s > 0 ? y0 + K * du * (1 - std::exp(-s / tau_s)) : y0;
}

StepStart log_incomplete_start(const StepRecord& r) {
  StepStart st;
  const std::size_t n = r.t.size();
  std::size_t first_after = 0;
  while (first_after < n && r.t[first_after] <= r.t_step) ++first_after;
  st.y0 = first_after >= 1 ? mean_of(r.y, first_after > 20 ? first_after - first_after / 2 : 0, first_after) : r.y[0];
  const std::size_t n_after = n - first_after;
  const std::size_t tail = std::max<std::size_t>(1, n_after / 10);
  const double y_end = mean_of(r.y, n - tail, n);
  const double duration = response_duration(r);
  st.y_ss = y_end;
  st.K = (y_end - st.y0) / r.du;
  st.tau_s = duration / 3;
  st.theta_s = 0;
  const double span = y_end - st.y0;
  if (span == 0) return st;
  // Only the transient is used: from where the (smoothed) response has made 5 % of its way to
  // the last level until it has made 90 % -- a long settled tail would flatten the line.
  const std::size_t w = std::max<std::size_t>(1, n_after / 100);
  double t_lo = r.t[first_after], t_hi = r.t.back();
  {
    bool lo_found = false;
    double acc = 0;
    for (std::size_t i = first_after; i < n; ++i) {
      acc += r.y[i];
      if (i >= first_after + w) acc -= r.y[i - w];
      const std::size_t cnt = std::min(w, i - first_after + 1);
      const double prog = (acc / static_cast<double>(cnt) - st.y0) / span;
      const double tc = r.t[i - (cnt - 1) / 2];
      if (!lo_found && prog >= 0.05) {
        t_lo = tc;
        lo_found = true;
      }
      if (prog >= 0.9) {
        t_hi = tc;
        break;
      }
    }
  }
  // The samples with t_lo <= t <= t_hi (times increase): the transient, searched once.
  const auto t_begin = r.t.begin() + static_cast<std::ptrdiff_t>(first_after);
  const auto i_lo = static_cast<std::size_t>(std::lower_bound(t_begin, r.t.end(), t_lo) - r.t.begin());
  const auto i_hi = static_cast<std::size_t>(std::upper_bound(t_begin, r.t.end(), t_hi) - r.t.begin());
  double best_r2 = -1;
  std::vector<double> tt, zz;
  tt.reserve(i_hi - std::min(i_lo, i_hi));
  zz.reserve(tt.capacity());
  for (double c : {0.03, 0.1, 0.3, 1.0, 3.0, 10.0}) {
    const double yss = y_end + c * span;
    tt.clear();
    zz.clear();
    for (std::size_t i = i_lo; i < i_hi; ++i) {
      const double ratio = (r.y[i] - yss) / (st.y0 - yss);  // 1 at the start, 0 at steady state
      if (ratio > 0.01 && ratio < 0.99) {
        tt.push_back(r.t[i]);
        zz.push_back(std::log(ratio));
      }
    }
    if (tt.size() < 3) continue;
    const auto [a, b, r2] = line_fit(tt, zz);
    if (!(b < 0) || r2 <= best_r2) continue;
    best_r2 = r2;
    st.y_ss = yss;
    st.tau_s = std::clamp(-1.0 / b, 1e-3 * duration, 10 * duration);
    // Z = -(t - t_step - theta) / tau crosses zero at t_step + theta.
    st.theta_s = std::clamp(-a / b - r.t_step, 0.0, 0.5 * duration);
    st.K = (yss - st.y0) / r.du;
    st.linearity_r2 = r2;
  }
  return st;
}

FitResult fit_step(const StepRecord& r, StepModel model, const LsqOptions& options) {
  check_record(r, model_name(model));
  // The times increase (check_record): the samples before the step are those before the first
  // at or after it.
  const auto before = static_cast<std::size_t>(std::lower_bound(r.t.begin(), r.t.end(), r.t_step) - r.t.begin());
  if (model == StepModel::fopdt && before < 3)
    throw FitError("fopdt: theta_s and y0 cannot both be identified without samples before the step (" +
                   std::to_string(before) +
                   " found); include the steady state before the step or use the first-order model (fo)");
  const double duration = response_duration(r);
  const StepStart st = log_incomplete_start(r);

  // Levenberg-Marquardt on the 4x4 normal equations to convergence by Ceres Solver's tests, with
  // the tolerances a Ceres solve of this problem uses (solve_normal_equations); the covariance
  // from the same normal matrix (fill_covariance). Only when that does not converge does Ceres
  // take over from where it stopped.
  LsqOptions ceres_opt = options;
  ceres_opt.compute_covariance = false;
  // Function and parameter tolerances of at least 1e-12, for both solvers: the polished start is
  // at the optimum to about 1e-10 in cost, and the default 1e-15 would only have the solver shrink
  // rejected steps for several more passes over the samples.
  ceres_opt.function_tolerance = std::max(options.function_tolerance, 1e-12);
  ceres_opt.parameter_tolerance = std::max(options.parameter_tolerance, 1e-12);
  lm_detail::Tolerances tol;
  tol.function = ceres_opt.function_tolerance;
  tol.parameter = ceres_opt.parameter_tolerance;
  tol.gradient = ceres_opt.gradient_tolerance;
  tol.max_iterations = ceres_opt.max_iterations;
  auto solve_from = [&](const StepStart& s) {
    LsqProblem prob;
    const double tmin = r.t.size() > 1 ? (r.t[1] - r.t[0]) * 1e-3 : 1e-9;
    prob.params = {
        {"K", r.gain_unit, s.K},
        {"tau_s", "s", s.tau_s, std::max(tmin, 1e-9), kTauMaxFactor * duration},
        {"theta_s", "s", model == StepModel::fo ? 0.0 : s.theta_s, 0.0, 0.9 * duration, model == StepModel::fo},
        {"y0", r.output_unit, s.y0}};
    double p[4], lo[4], hi[4];
    bool fixed[4];
    for (int j = 0; j < 4; ++j) {
      const auto& ps = prob.params[static_cast<std::size_t>(j)];
      p[j] = std::clamp(ps.start, ps.lower, ps.upper);
      lo[j] = ps.lower;
      hi[j] = ps.upper;
      fixed[j] = ps.fixed;
    }
    const NormalSolve ns = solve_normal_equations(r, p, lo, hi, fixed, tol);
    if (ns.confirmed.converged()) {
      // One buffer of the record's length, not zeroed, serves in turn the residuals at the
      // solution, their whiteness test and the median sample interval.
      const auto buffer = std::make_unique_for_overwrite<double[]>(r.t.size());
      const std::span<double> scratch(buffer.get(), r.t.size());
      FitResult fr = normal_solve_result(r, model, prob.params, p, ns, scratch);
      if (options.compute_covariance) fill_covariance(fr, r, options, &ns.JtJ, scratch);
      return fr;
    }
    for (int j = 0; j < 4; ++j) prob.params[static_cast<std::size_t>(j)].start = p[j];
    prob.num_residuals = static_cast<int>(r.t.size());
    prob.observed = r.y;
    prob.residuals_and_jacobian = [&r](const double* q, double* res, double* jac) {
      static constexpr std::size_t cols[4] = {0, 1, 2, 3};
      step_residuals(r, q[0], q[1], q[2], q[3], res, jac, 4, cols);
      return true;
    };
    FitResult fr = solve_least_squares(model_name(model), prob, ceres_opt);
    if (options.compute_covariance) fill_covariance(fr, r, options, nullptr);
    return fr;
  };

  FitResult f;
  try {
    f = solve_from(st);
  } catch (const FitError&) {
    StepStart alt = st;  // fallback: plain start without the log transform
    alt.tau_s = duration / 3;
    alt.theta_s = 0;
    alt.K = (r.y.back() - st.y0) / r.du;
    f = solve_from(alt);
  }
  check_identifiable(f, &r, duration, options.compute_covariance);
  return f;
}

}  // namespace tunekit::fitting
