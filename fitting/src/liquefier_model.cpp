// The whole-record liquefier model (liquefier_model.hpp): simulation, start values, the Ceres
// fit, the intervals and the choice of the linear model.
#include "tunekit/fitting/liquefier_model.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include <fmt/format.h>

#include "liquefier_model_sim.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/profile_likelihood.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::fitting {
namespace {

using liquefier_detail::InputTrack;
using liquefier_detail::SimParams;
using liquefier_detail::simulate;

/// The stored volume at steady input u (the state a settled record starts in).
double steady_volume(double a, double b, double u) { return u > 0 ? a * std::pow(u, b + 1) / (b + 1) : 0.0; }

constexpr double kThetaMaxFraction = 0.25;  // theta at most this share of the record
constexpr std::size_t kThinTarget = 3000;   // samples of the thinned record the start is found on
constexpr int kMaxSubsteps = 64;            // sub-steps of one sample interval at most

struct Rec {
  std::vector<double> t, u, y;
};

/// The least-squares problem of one record; parameters tau_ref_s, b, theta_s, g, c, V0 (the
/// stored volume at the first sample: a record need not start settled).
struct ModelProblem {
  Rec rec;
  InputTrack input;                ///< the commanded input (the record's own samples, or its track)
  std::vector<std::size_t> kinks;  ///< where the input's slope changes (input_kinks)
  bool volume = false;
  double q_ref = 1;
  int substeps = 1;     ///< sub-steps in the longest sample interval (reported)
  double h_max = 0;     ///< longest sub-step (s): an eighth of the smallest time constant
  bool fix_v0 = false;  ///< the record starts empty: V0 held at 0 (its derivative vanishes there)
  LsqProblem lsq;
  std::vector<double> sim, sens;  ///< scratch: the simulated signal and its sensitivities
};

void bind(ModelProblem& mp) {
  ModelProblem* self = &mp;
  mp.lsq.num_residuals = static_cast<int>(mp.rec.t.size());
  mp.lsq.observed = mp.rec.y;
  // The simulation computes the state the same way with and without its sensitivities.
  mp.lsq.same_residuals_with_jacobian = true;
  mp.lsq.residuals_and_jacobian = [self](const double* p, double* r, double* jac) {
    const Rec& rc = self->rec;
    const std::size_t n = rc.t.size();
    const double ln_qref = std::log(self->q_ref);
    if (!(p[0] > 0) || !(p[1] > -1) || !(p[2] >= 0) || !(p[5] >= 0)) return false;
    // ln a = ln tau_ref - b ln Q_ref.
    const SimParams sp{std::log(p[0]) - p[1] * ln_qref, p[1], p[2], p[5], !self->lsq.params[1].fixed};
    self->sim.resize(n);
    if (jac != nullptr) self->sens.resize(4 * n);
    simulate(rc.t.data(), n, self->input, sp, self->volume, self->h_max > 0 ? kMaxSubsteps : self->substeps,
             self->h_max, self->sim.data(), jac != nullptr ? self->sens.data() : nullptr);
    const double* s = self->sim.data();
    for (std::size_t i = 0; i < n; ++i) {
      r[i] = p[3] * s[i] + p[4] - rc.y[i];
      if (!std::isfinite(r[i])) return false;
    }
    if (jac == nullptr) return true;
    const double inv_tau = 1.0 / p[0];
    for (std::size_t i = 0; i < n; ++i) {
      const double* d = self->sens.data() + 4 * i;  // d/d(ln a, b, theta, V0)
      double* row = jac + i * 6;
      row[0] = p[3] * d[0] * inv_tau;
      row[1] = p[3] * (d[1] - ln_qref * d[0]);
      row[2] = p[3] * d[2];
      row[3] = s[i];
      row[4] = 1.0;
      row[5] = p[3] * d[3];
    }
    return true;
  };
}

void check_record(const LiquefierRecord& r) {
  const std::size_t n = r.t.size();
  if (r.u.size() != n || r.y.size() != n)
    throw InputError("whole-record model: time, input and output differ in length");
  if (n < 20) throw InputError(fmt::format("whole-record model: too few samples ({}); at least 20 are needed", n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(r.t[i]) || !std::isfinite(r.u[i]) || !std::isfinite(r.y[i]))
      throw InputError("whole-record model: NaN or infinite sample");
    if (i > 0 && !(r.t[i] > r.t[i - 1]))
      throw InputError(fmt::format("whole-record model: time is not increasing at sample {}", i + 1));
    if (r.u[i] < 0)
      throw InputError(
          fmt::format("whole-record model: the input is negative at t = {:.4g} s; the store is fed by a flow or feed "
                      "of at least 0 (a retraction is outside the model)",
                      r.t[i]));
  }
  if (r.input_t.size() != r.input_u.size())
    throw InputError("whole-record model: the commanded input's instants and values differ in length");
  for (std::size_t i = 0; i < r.input_t.size(); ++i) {
    if (!std::isfinite(r.input_t[i]) || !std::isfinite(r.input_u[i]))
      throw InputError("whole-record model: NaN or infinite point in the commanded input");
    if (i > 0 && r.input_t[i] < r.input_t[i - 1])
      throw InputError(fmt::format("whole-record model: the commanded input's time goes back at point {}", i + 1));
    if (r.input_u[i] < 0)
      throw InputError(
          fmt::format("whole-record model: the commanded input is negative at t = {:.4g} s", r.input_t[i]));
  }
  const auto [lo, hi] = std::minmax_element(r.u.begin(), r.u.end());
  if (!(*hi > *lo)) throw InputError("whole-record model: the input is constant; nothing excites the liquefier");
  const auto [ylo, yhi] = std::minmax_element(r.y.begin(), r.y.end());
  if (!(*yhi > *ylo)) throw InputError("whole-record model: the output is constant; there is no response to fit");
}

double positive_median(const std::vector<double>& u) {
  std::vector<double> pos;
  for (double v : u)
    if (v > 0) pos.push_back(v);
  return median(pos);
}

/// g, c by linear least squares for y = g s + c; returns the residual sum of squares.
double linear_gc(const std::vector<double>& s, const std::vector<double>& y, double& g, double& c) {
  const double n = static_cast<double>(s.size());
  double ms = 0, my = 0;
  for (std::size_t i = 0; i < s.size(); ++i) ms += s[i], my += y[i];
  ms /= n, my /= n;
  double sss = 0, ssy = 0, syy = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    sss += (s[i] - ms) * (s[i] - ms);
    ssy += (s[i] - ms) * (y[i] - my);
    syy += (y[i] - my) * (y[i] - my);
  }
  g = sss > 0 ? ssy / sss : 0;
  c = my - g * ms;
  return syy - g * ssy;
}

Rec thinned(const LiquefierRecord& r) {
  const std::size_t m = std::max<std::size_t>(1, r.t.size() / kThinTarget);
  Rec out;
  for (std::size_t i = 0; i < r.t.size(); i += m) {
    out.t.push_back(r.t[i]);
    out.u.push_back(r.u[i]);
    out.y.push_back(r.y[i]);
  }
  return out;
}

/// The best linear first-order model (b = 0), settled at the start, on a grid of tau and theta:
/// {tau, theta, g, c}.
std::array<double, 4> linear_grid_start(const Rec& r, const InputTrack& input, bool volume) {
  const std::size_t n = r.t.size();
  const double T = r.t.back() - r.t.front();
  const double dt = T / static_cast<double>(n - 1);
  const double tau_lo = std::max(dt, T * 1e-4), tau_hi = T / 4;
  std::array<double, 4> best{tau_lo, 0, 1, 0};
  double best_rss = std::numeric_limits<double>::infinity();
  std::vector<double> s(n);
  const int nt = 14;
  for (int i = 0; i < nt; ++i) {
    const double tau = tau_lo * std::pow(tau_hi / tau_lo, i / double(nt - 1));
    for (double th : {0.0, 1.0, 2.0, 4.0, 8.0, 16.0}) {
      const double theta = std::min(th * dt, kThetaMaxFraction * T * 0.5);
      simulate(r.t.data(), n, input, SimParams{std::log(tau), 0.0, theta, tau * r.u.front()}, volume, 1, 0.0, s.data(),
               nullptr);
      double g = 0, c = 0;
      const double rss = linear_gc(s, r.y, g, c);
      if (rss < best_rss) best_rss = rss, best = {tau, theta, g, c};
    }
  }
  return best;
}

std::vector<ParamSpec> specs(const ModelProblem& mp, const std::array<double, 6>& start, const LiquefierFitOptions& o,
                             const LiquefierRecord& rec, bool fix_b) {
  const double T = mp.rec.t.back() - mp.rec.t.front();
  const std::string in = rec.input_unit, out = rec.output_unit;
  // Output per input: "1" when both are the same unit (a width against a width, a feed against a feed).
  const std::string gunit = mp.volume ? out + "/(" + in + ".s)" : out == in ? "1" : out + "/(" + in + ")";
  return {{"tau_ref_s", "s", start[0], 1e-6 * T, 10 * T},
          {"b", "1", fix_b ? 0.0 : std::clamp(start[1], o.b_lower, o.b_upper), o.b_lower, o.b_upper, fix_b},
          {"theta_s", "s", std::clamp(start[2], 0.0, kThetaMaxFraction * T), 0.0, kThetaMaxFraction * T},
          {"g", gunit, start[3]},
          {"c", out, start[4]},
          {"V0", in + ".s", mp.fix_v0 ? 0.0 : std::max(start[5], 0.0), 0.0, std::numeric_limits<double>::infinity(),
           mp.fix_v0}};
}

using HoldFunction = std::function<void(std::vector<double>&, std::vector<bool>&)>;

FitResult solve(ModelProblem& mp, const std::array<double, 6>& start, const LiquefierFitOptions& o,
                const LiquefierRecord& rec, bool fix_b, bool covariance, const HoldFunction& hold = {}) {
  mp.lsq.params = specs(mp, start, o, rec, fix_b);
  // The exponential step is exact for the linear model: one sub-step.
  if (fix_b) {
    mp.substeps = 1;
    mp.h_max = 0;
  } else {
    const double a = start[0] * std::pow(mp.q_ref, -start[1]);
    const std::vector<double> levels(mp.input.u, mp.input.u + mp.input.n);
    mp.h_max = liquefier_max_substep_s(levels, a, start[1]);
    mp.substeps = liquefier_substeps(mp.rec.t, levels, a, start[1]);
  }
  LsqOptions lo;
  lo.compute_covariance = covariance;
  lo.require_convergence = covariance;
  lo.max_iterations = covariance ? 200 : 60;
  lo.function_tolerance = 1e-10;
  lo.parameter_tolerance = 1e-10;
  lo.gradient_tolerance = 1e-12;
  lo.hold_before_covariance = hold;
  return solve_least_squares(fix_b ? "liquefier_linear" : "liquefier_store", mp.lsq, lo);
}

std::array<double, 6> values(const FitResult& f) {
  return {f.params[0].value, f.params[1].value, f.params[2].value,
          f.params[3].value, f.params[4].value, f.params[5].value};
}

/// The full record's fit with its covariance, in one solve: a stored volume at the start that
/// ends at (or within 0.1 % of the largest stored volume from) its bound 0 is held there for the
/// covariance, where the output does not depend on it (the record starts with an empty
/// liquefier), and stays held for the profiles and the refits that follow. Only when it had to be
/// moved onto the bound are the others solved again.
FitResult solve_full(ModelProblem& full, const std::array<double, 6>& start, const LiquefierFitOptions& o,
                     const LiquefierRecord& rec, bool fix_b) {
  bool moved = false;
  HoldFunction hold;
  if (!full.fix_v0) {
    const double umax = *std::max_element(rec.u.begin(), rec.u.end());
    hold = [&full, &moved, umax](std::vector<double>& x, std::vector<bool>& held) {
      const double a = x[0] * std::pow(full.q_ref, -x[1]);
      if (x[5] <= 1e-3 * steady_volume(a, x[1], umax)) {
        held[5] = true;
        moved = x[5] != 0.0;
        x[5] = 0.0;
      }
    };
  }
  FitResult f = solve(full, start, o, rec, fix_b, true, hold);
  if (!full.fix_v0 && f.params[5].fixed) {
    full.fix_v0 = true;
    full.lsq.params = specs(full, values(f), o, rec, fix_b);
    if (moved) f = solve(full, values(f), o, rec, fix_b, true);
  }
  return f;
}

std::vector<double> residuals_at(ModelProblem& mp, const FitResult& f) {
  std::vector<double> r(mp.rec.t.size());
  const auto p = values(f);
  mp.lsq.residuals_and_jacobian(p.data(), r.data(), nullptr);
  return r;
}

/// Widens the Wald intervals by sqrt(f), ends them at the parameters' domain (a dead time that
/// ended at 0 has no interval below it) and adds a.
void finish_intervals(FitResult& f, const std::vector<ParamSpec>& specs, double q_ref, double factor, double confidence,
                      const std::string& input_unit) {
  const int dof = f.diagnostics.num_observations - f.diagnostics.num_parameters;
  const double tq = t_multiplier(confidence, dof);
  const double w = std::sqrt(factor);
  for (std::size_t j = 0; j < f.params.size(); ++j) {
    auto& p = f.params[j];
    if (p.fixed) continue;
    p.std_error *= w;
    p.ci95_lo = std::max(p.value - tq * p.std_error, specs[j].lower);
    p.ci95_hi = std::min(p.value + tq * p.std_error, specs[j].upper);
    p.ci95_method = "wald";
  }
  // a = tau_ref Q_ref^-b; ln a = ln tau_ref - b ln Q_ref (delta method in ln).
  const std::size_t k = f.params.size();
  const double L = std::log(q_ref);
  const auto& tau = f.params[0];
  const auto& b = f.params[1];
  double var = std::pow(tau.std_error / tau.value, 2);
  if (!b.fixed && f.covariance.size() == k * k) {
    const double cov_tb = f.covariance[0 * k + 1] * factor;
    var += L * L * b.std_error * b.std_error - 2 * L * cov_tb / tau.value;
  }
  Param a;
  a.name = "a";
  a.unit = fmt::format("s.({})^-b", input_unit);
  a.value = tau.value * std::exp(-b.value * L);
  const double se_ln = std::sqrt(std::max(var, 0.0));
  a.std_error = a.value * se_ln;
  a.ci95_lo = a.value * std::exp(-tq * se_ln);
  a.ci95_hi = a.value * std::exp(tq * se_ln);
  a.ci95_method = "wald";
  f.derived = {a};
}

/// Profile intervals of b (index 1, when free) and theta (index 2) with the widened threshold.
int profile(ModelProblem& mp, FitResult& f, double factor, double confidence) {
  ProfileOptions po;
  po.confidence = confidence;
  po.variance_factor = factor;
  po.inner_max_iterations = 40;
  int solves = 0;
  for (int idx : {1, 2}) {
    auto& p = f.params[static_cast<std::size_t>(idx)];
    if (p.fixed) continue;
    // The profile starts from the unwidened standard error (profile_interval widens it itself).
    FitResult base = f;
    base.params[static_cast<std::size_t>(idx)].std_error = p.std_error / std::sqrt(factor);
    const ProfileInterval pi = profile_interval(mp.lsq, base, idx, po);
    solves += pi.solves;
    p.ci95_lo = std::min(pi.lo, p.value);
    p.ci95_hi = std::max(pi.hi, p.value);
    p.ci95_method = "profile-likelihood";
    if (pi.lo_at_bound || pi.hi_at_bound)
      f.warnings.push_back(fmt::format("the 95 % profile-likelihood interval of {} is not closed by the data", p.name));
  }
  return solves;
}

}  // namespace

std::string to_string(LiquefierSensor s) { return s == LiquefierSensor::flow ? "flow" : "pressure"; }

double liquefier_tau_s(const LiquefierParams& p, double q) { return p.a * std::pow(q, p.b); }
double liquefier_volume(const LiquefierParams& p, double q) {
  return q > 0 ? p.a * std::pow(q, p.b + 1) / (p.b + 1) : 0.0;
}

double liquefier_max_substep_s(const std::vector<double>& u, double a, double b) {
  // tau = a u^b is monotonic in u: its smallest value is at the smallest or the largest input.
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (double v : u)
    if (v > 0) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(hi > 0)) return 0;
  const double tau_min = std::min(a * std::pow(lo, b), a * std::pow(hi, b));
  if (!(tau_min > 0) || !std::isfinite(tau_min)) return 0;
  return tau_min / 8;
}

int liquefier_substeps(const std::vector<double>& t, const std::vector<double>& u, double a, double b) {
  double dt_max = 0;
  for (std::size_t i = 1; i < t.size(); ++i) dt_max = std::max(dt_max, t[i] - t[i - 1]);
  const double h = liquefier_max_substep_s(u, a, b);
  if (!(h > 0)) return 1;
  return std::clamp(static_cast<int>(std::ceil(dt_max / h)), 1, kMaxSubsteps);
}

namespace {

/// The sensor-free signal (and with sens its derivatives with respect to ln a, b, theta, V0).
std::vector<double> simulate_signal(const std::vector<double>& t, const std::vector<double>& tu,
                                    const std::vector<double>& u, const LiquefierParams& p, LiquefierSensor sensor,
                                    int substeps, std::vector<double>* sens) {
  if (tu.size() != u.size() || t.empty() || u.empty())
    throw InputError("simulate_liquefier: time and input differ in length");
  if (!(p.a > 0) || !(p.b > -1) || !(p.theta_s >= 0))
    throw InputError("simulate_liquefier: a must be positive, b above -1 and theta at least 0");
  // A fixed count when given; else sized per sample interval.
  const int ns = substeps > 0 ? substeps : kMaxSubsteps;
  const double h_max = substeps > 0 ? 0.0 : liquefier_max_substep_s(u, p.a, p.b);
  std::vector<double> s(t.size());
  // Settled at the input in force at the first instant (before any step of the track).
  std::size_t first = 0;
  while (first + 1 < tu.size() && tu[first + 1] <= t.front() - p.theta_s) ++first;
  const double v0 = std::isfinite(p.v0) ? p.v0 : steady_volume(p.a, p.b, u[first]);
  if (sens != nullptr) sens->assign(4 * t.size(), 0.0);
  simulate(t.data(), t.size(), InputTrack{tu.data(), u.data(), u.size()}, SimParams{std::log(p.a), p.b, p.theta_s, v0},
           sensor == LiquefierSensor::pressure, ns, h_max, s.data(), sens != nullptr ? sens->data() : nullptr);
  return s;
}

}  // namespace

std::vector<double> simulate_liquefier(const std::vector<double>& t, const std::vector<double>& u,
                                       const LiquefierParams& p, LiquefierSensor sensor, int substeps) {
  std::vector<double> s = simulate_signal(t, t, u, p, sensor, substeps, nullptr);
  for (double& v : s) v = p.g * v + p.c;
  return s;
}

std::vector<double> simulate_liquefier(const std::vector<double>& t, const std::vector<double>& input_t,
                                       const std::vector<double>& input_u, const LiquefierParams& p,
                                       LiquefierSensor sensor, int substeps) {
  std::vector<double> s = simulate_signal(t, input_t, input_u, p, sensor, substeps, nullptr);
  for (double& v : s) v = p.g * v + p.c;
  return s;
}

std::vector<std::array<double, 4>> liquefier_sensitivities(const std::vector<double>& t, const std::vector<double>& u,
                                                           const LiquefierParams& p, LiquefierSensor sensor,
                                                           int substeps) {
  if (t.size() != u.size()) throw InputError("liquefier_sensitivities: time and input differ in length");
  return liquefier_sensitivities(t, t, u, p, sensor, substeps);
}

std::vector<std::array<double, 4>> liquefier_sensitivities(const std::vector<double>& t,
                                                           const std::vector<double>& input_t,
                                                           const std::vector<double>& input_u, const LiquefierParams& p,
                                                           LiquefierSensor sensor, int substeps) {
  std::vector<double> d;
  (void)simulate_signal(t, input_t, input_u, p, sensor, substeps, &d);
  std::vector<std::array<double, 4>> out(t.size());
  for (std::size_t i = 0; i < t.size(); ++i)
    out[i] = {p.g * d[4 * i] / p.a, p.g * d[4 * i + 1], p.g * d[4 * i + 2], p.g * d[4 * i + 3]};
  return out;
}

LiquefierParams LiquefierModelFit::params() const {
  LiquefierParams p;
  p.a = fit.derived.empty() ? kNaN : fit.derived.front().value;
  p.b = fit.value("b");
  p.theta_s = fit.value("theta_s");
  p.g = fit.value("g");
  p.c = fit.value("c");
  p.v0 = fit.value("V0");
  return p;
}

LiquefierModelFit fit_liquefier_model(const LiquefierRecord& rec, const LiquefierFitOptions& o) {
  check_record(rec);
  LiquefierModelFit out;
  out.sensor = rec.sensor;
  out.reference_input = positive_median(rec.u);
  const bool volume = rec.sensor == LiquefierSensor::pressure;

  // Start: linear grid, then the model on the thinned record.
  ModelProblem thin;
  thin.rec = thinned(rec);
  thin.volume = volume;
  thin.q_ref = out.reference_input;
  // The commanded input: the record's own track when it carries one, else its samples; the
  // thinned record keeps all of it (only the outputs are thinned).
  thin.input = rec.input_t.empty() ? InputTrack{rec.t.data(), rec.u.data(), rec.t.size()}
                                   : InputTrack{rec.input_t.data(), rec.input_u.data(), rec.input_t.size()};
  thin.kinks = liquefier_detail::input_kinks(thin.input);
  thin.input.kinks = thin.kinks.data();
  thin.input.n_kinks = thin.kinks.size();
  bind(thin);
  const auto g0 = linear_grid_start(thin.rec, thin.input, volume);
  std::array<double, 6> start{g0[0], 0.0, g0[1], g0[2], g0[3], g0[0] * rec.u.front()};
  FitResult best;
  bool have = false;
  for (double b0 : {0.0, -0.5}) {
    if (!o.fit_b && b0 != 0.0) continue;
    std::array<double, 6> s0 = start;
    s0[1] = b0;
    s0[5] = steady_volume(start[0] * std::pow(out.reference_input, -b0), b0, rec.u.front());
    try {
      FitResult f = solve(thin, s0, o, rec, !o.fit_b, false);
      if (!have || f.diagnostics.rss < best.diagnostics.rss) best = f, have = true;
    } catch (const FitError&) {
    }
  }
  if (!have) throw FitError("whole-record model: no start value led to a fit of the record");

  ModelProblem full;
  full.rec = {rec.t, rec.u, rec.y};
  full.volume = volume;
  full.q_ref = out.reference_input;
  full.input = thin.input;
  full.kinks = thin.kinks;
  full.input.kinks = full.kinks.data();
  bind(full);
  // A record that starts with an empty liquefier ends the thinned fit with V0 at its bound 0,
  // where the output does not depend on it: V0 is then held at 0.
  {
    const auto v = values(best);
    const double a0 = v[0] * std::pow(out.reference_input, -v[1]);
    const double umax = *std::max_element(rec.u.begin(), rec.u.end());
    full.fix_v0 = v[5] <= 1e-6 * steady_volume(a0, v[1], umax);
  }
  FitResult nl = solve_full(full, values(best), o, rec, !o.fit_b);
  out.substeps = full.substeps;
  if (!o.fit_b) {
    out.variance_factor = residual_variance_factor(residuals_at(full, nl));
    finish_intervals(nl, full.lsq.params, out.reference_input, out.variance_factor, o.confidence, rec.input_unit);
    if (o.profile) out.profile_solves += profile(full, nl, out.variance_factor, o.confidence);
    out.linear_chosen = true;
    out.fit = out.nonlinear = nl;
    return out;
  }
  out.variance_factor = residual_variance_factor(residuals_at(full, nl));
  const FitResult nl_raw = nl;
  finish_intervals(nl, full.lsq.params, out.reference_input, out.variance_factor, o.confidence, rec.input_unit);
  if (o.profile) out.profile_solves += profile(full, nl, out.variance_factor, o.confidence);

  // The linear model: b held at 0, refitted; the F-test of b = 0 at the confidence level.
  // Its start: the linear model on the thinned record, from the free fit with b = 0.
  std::array<double, 6> lin_start = values(nl_raw);
  lin_start[1] = 0.0;
  thin.fix_v0 = full.fix_v0;
  try {
    lin_start = values(solve(thin, lin_start, o, rec, true, false));
  } catch (const FitError&) {
  }
  FitResult lin = solve_full(full, lin_start, o, rec, true);
  const int dof = nl.diagnostics.num_observations - nl.diagnostics.num_parameters;
  const double s2 = nl_raw.diagnostics.rss / dof;
  const double tq = t_multiplier(o.confidence, dof);
  out.f_statistic = (lin.diagnostics.rss - nl_raw.diagnostics.rss) / (s2 * out.variance_factor);
  out.f_threshold = tq * tq;
  out.linear_chosen = out.f_statistic <= out.f_threshold;
  out.nonlinear = nl;
  if (out.linear_chosen) {
    finish_intervals(lin, full.lsq.params, out.reference_input, out.variance_factor, o.confidence, rec.input_unit);
    if (o.profile) out.profile_solves += profile(full, lin, out.variance_factor, o.confidence);
    out.fit = lin;
  } else {
    out.fit = nl;
  }
  return out;
}

}  // namespace tunekit::fitting
