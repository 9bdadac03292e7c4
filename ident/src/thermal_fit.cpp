// The hot end's thermal model fitted to a whole record (thermal_fit.hpp).
#include "tunekit/ident/thermal_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/modal_fit.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {

namespace {

// The parameters in the solver's order.
enum ThermalParam : std::size_t { kP, kC, kR, kA, kF, kH, kAmbient, kStart, kThermalParams };
constexpr std::array<const char*, kThermalParams> kThermalNames{"heater_power_w",
                                                                "block_heat_capacity_j_per_k",
                                                                "sensor_responsiveness_per_s",
                                                                "ambient_transfer_w_per_k",
                                                                "fan_transfer_w_per_k",
                                                                "filament_heat_capacity_j_per_k_mm",
                                                                "ambient_c",
                                                                "start_c"};
constexpr std::array<const char*, kThermalParams> kThermalUnits{"W",   "J/K",    "1/s",  "W/K",
                                                                "W/K", "J/K/mm", "degC", "degC"};
// Fewest fitted samples: seven parameters need several samples each.
constexpr std::size_t kMinFittedSamples = 20;
// A pair of estimates this correlated is reported (the "correlations that matter").
constexpr double kReportedCorrelation = 0.7;
// Sensor rates tried for the start: from a slow thermistor in a brass boss to a cartridge-type
// sensor (Marlin's MPC configurations give 0.1-0.5 1/s).
constexpr std::array<double, 5> kStartSensorRates{0.05, 0.1, 0.2, 0.4, 0.8};
// Samples either side of a centred difference for the start's heat balance.
constexpr std::size_t kSlopeHalfWindow = 2;

double at_or_zero(const std::vector<double>& v, std::size_t i) { return v.empty() ? 0.0 : v[i]; }

ThermalModel model_of(const double* p) { return {p[kP], p[kC], p[kR], p[kA], p[kF], p[kH], p[kAmbient]}; }

// Block and sensor over one interval of constant inputs, exactly (thermal_model.hpp).
void step_interval(const ThermalModel& m, double u, double f, double v, double h, double& block, double& sensor) {
  const double loss = m.ambient_transfer_w_per_k + f * (m.fan_transfer_w_per_k - m.ambient_transfer_w_per_k) +
                      m.filament_heat_capacity_j_per_k_mm * v;
  const double a = loss / m.block_heat_capacity_j_per_k, r = m.sensor_responsiveness_per_s;
  const double settle = m.ambient_c + u * m.heater_power_w / loss;
  const double d0 = block - settle, x = (a - r) * h;
  const double phi = std::abs(x) < 1e-12 ? 1.0 : std::expm1(x) / x;
  const double ea = std::exp(-a * h), er = std::exp(-r * h);
  sensor = settle + d0 * r * ea * h * phi + (sensor - settle) * er;
  block = settle + d0 * ea;
}

bool has_positive(const std::vector<double>& v) {
  return std::any_of(v.begin(), v.end(), [](double x) { return x > 0; });
}

// Start values from the heat balance P u = C dT/dt + (T - T_a) (A + (F - A) f + H v), the sensor
// taken for the block, solved by linear least squares for C, A, F - A and H.
std::array<double, kThermalParams> start_values(const ThermalRecord& r, std::size_t n, double power_w, bool fan,
                                                bool feed) {
  const double ta = r.temp_c[0];
  Eigen::MatrixXd X(static_cast<Eigen::Index>(n), 4);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  X.setZero();
  y.setZero();
  for (std::size_t i = kSlopeHalfWindow; i + kSlopeHalfWindow < n; ++i) {
    const std::size_t a = i - kSlopeHalfWindow, b = i + kSlopeHalfWindow;
    const double slope = (r.temp_c[b] - r.temp_c[a]) / (r.t_s[b] - r.t_s[a]);
    const double dt = r.temp_c[i] - ta;
    const auto row = static_cast<Eigen::Index>(i);
    X.row(row) << slope, dt, dt * at_or_zero(r.fan_duty, i), dt * at_or_zero(r.feed_mm_s, i);
    y(row) = power_w * r.heater_duty[i];
  }
  if (!fan) X.col(2).setZero();
  if (!feed) X.col(3).setZero();
  const Eigen::VectorXd c = fitting::least_squares_solve(X, y);
  std::array<double, kThermalParams> p{};
  p[kP] = power_w;
  p[kC] = std::clamp(c(0), 1.0, 1000.0);
  p[kA] = std::clamp(c(1), 1e-3, 10.0);
  p[kF] = p[kA] + (fan ? std::clamp(c(2), 0.0, 10.0) : 0.0);
  p[kH] = feed ? std::clamp(c(3), 1e-4, 1.0) : 0.0;
  p[kAmbient] = ta;
  p[kStart] = r.temp_c[0];
  p[kR] = kStartSensorRates[2];
  return p;
}

double sum_squares(const std::array<double, kThermalParams>& p, const ThermalRecord& r, std::size_t n) {
  const auto pred = simulate_thermal_record(model_of(p.data()), p[kStart], r);
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += (pred[i] - r.temp_c[i]) * (pred[i] - r.temp_c[i]);
  return s;
}

fitting::LsqProblem thermal_problem(const ThermalRecord& r, std::size_t n, const std::array<double, kThermalParams>& p0,
                                    bool fan, bool feed) {
  fitting::LsqProblem prob;
  const std::array<double, kThermalParams> lo{0, 0.01, 1e-3, 1e-5, 1e-5, 0, -60, -60};
  const std::array<double, kThermalParams> hi{1e4, 1e5, 50, 100, 100, 10, 200, 600};
  for (std::size_t j = 0; j < kThermalParams; ++j)
    prob.params.push_back({kThermalNames[j], kThermalUnits[j], p0[j], lo[j], hi[j], false});
  prob.params[kP].fixed = true;
  prob.params[kF].fixed = !fan;
  prob.params[kH].fixed = !feed;
  prob.num_residuals = static_cast<int>(n);
  prob.observed.assign(r.temp_c.begin(), r.temp_c.begin() + static_cast<std::ptrdiff_t>(n));
  prob.residuals = [&r, n, fan](const double* p, double* res) {
    std::array<double, kThermalParams> q;
    std::copy(p, p + kThermalParams, q.begin());
    if (!fan) q[kF] = q[kA];
    const auto pred = simulate_thermal_record(model_of(q.data()), q[kStart], r);
    for (std::size_t i = 0; i < n; ++i) {
      res[i] = pred[i] - r.temp_c[i];
      if (!std::isfinite(res[i])) return false;
    }
    return true;
  };
  return prob;
}

std::vector<ThermalCorrelation> strong_correlations(const fitting::FitResult& fit) {
  std::vector<ThermalCorrelation> out;
  const std::size_t n = fit.params.size();
  if (fit.covariance.size() != n * n) return out;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (fit.params[i].fixed || fit.params[j].fixed) continue;
      const double d = std::sqrt(fit.covariance[i * n + i] * fit.covariance[j * n + j]);
      if (!(d > 0)) continue;
      const double rij = fit.covariance[i * n + j] / d;
      if (std::abs(rij) >= kReportedCorrelation) out.push_back({fit.params[i].name, fit.params[j].name, rij});
    }
  return out;
}

// The held-out part's steps: its runs of samples with one fan duty and one feed, each named by
// the input that came on (against the run before), with its prediction's RMS error. A run of
// fewer than kMinStepSamples (the record's last tick) is not a step.
constexpr std::size_t kMinStepSamples = 3;
std::vector<HeldOutStep> held_out_steps(const ThermalRecord& r, std::size_t first, const std::vector<double>& pred) {
  std::vector<HeldOutStep> steps;
  const std::size_t n = r.t_s.size();
  double fan_before = first > 0 ? at_or_zero(r.fan_duty, first - 1) : 0;
  double feed_before = first > 0 ? at_or_zero(r.feed_mm_s, first - 1) : 0;
  for (std::size_t a = first; a < n;) {
    const double fan = at_or_zero(r.fan_duty, a), feed = at_or_zero(r.feed_mm_s, a);
    std::size_t b = a + 1;
    while (b < n && at_or_zero(r.fan_duty, b) == fan && at_or_zero(r.feed_mm_s, b) == feed) ++b;
    if (b - a >= kMinStepSamples) {
      // Named by the input that came on; else (both went off) by the one that changed.
      const bool fan_on = fan > 0 && fan != fan_before, feed_on = feed > 0 && feed != feed_before;
      const bool fan_step = fan_on || (!feed_on && fan != fan_before);
      HeldOutStep s{fan_step ? "fan" : "feed", r.t_s[a], r.t_s[b - 1], fan_step ? fan_before : feed_before,
                    fan_step ? fan : feed,     0,        b - a};
      double ss = 0;
      for (std::size_t i = a; i < b; ++i) ss += (pred[i] - r.temp_c[i]) * (pred[i] - r.temp_c[i]);
      s.rms_c = std::sqrt(ss / static_cast<double>(b - a));
      steps.push_back(s);
    }
    fan_before = fan;
    feed_before = feed;
    a = b;
  }
  return steps;
}

void check_finite_in(const std::vector<double>& v, const char* name, double lo, double hi) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]) || v[i] < lo || v[i] > hi)
      throw InputError(
          fmt::format("thermal record: {} at sample {} is {:g}, outside [{:g}, {:g}]", name, i + 1, v[i], lo, hi));
}

}  // namespace

void check_thermal_record(const ThermalRecord& r) {
  const std::size_t n = r.t_s.size();
  if (r.temp_c.size() != n || r.heater_duty.size() != n)
    throw InputError(fmt::format("thermal record: {} times, {} temperatures and {} heater duties: the sizes differ", n,
                                 r.temp_c.size(), r.heater_duty.size()));
  for (const auto* v : {&r.fan_duty, &r.feed_mm_s, &r.target_c})
    if (!v->empty() && v->size() != n)
      throw InputError(fmt::format("thermal record: a column of {} samples beside {} times", v->size(), n));
  const double inf = std::numeric_limits<double>::infinity();
  check_finite_in(r.t_s, "time", -inf, inf);
  check_finite_in(r.temp_c, "temperature", -100, 1000);
  check_finite_in(r.heater_duty, "heater duty", 0, 1);
  check_finite_in(r.fan_duty, "fan duty", 0, 1);
  check_finite_in(r.feed_mm_s, "feed", 0, 1000);
  for (std::size_t i = 1; i < n; ++i)
    if (!(r.t_s[i] > r.t_s[i - 1]))
      throw InputError(fmt::format("thermal record: time does not increase at sample {} ({:g} s after {:g} s)", i + 1,
                                   r.t_s[i], r.t_s[i - 1]));
}

std::vector<double> simulate_thermal_record(const ThermalModel& m, double start_c, const ThermalRecord& r) {
  const std::size_t n = r.t_s.size();
  std::vector<double> out(n);
  double block = start_c, sensor = start_c;
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = sensor;
    if (i + 1 < n)
      step_interval(m, r.heater_duty[i], at_or_zero(r.fan_duty, i), at_or_zero(r.feed_mm_s, i), r.t_s[i + 1] - r.t_s[i],
                    block, sensor);
  }
  return out;
}

ThermalFit fit_thermal_record(const ThermalRecord& r, const ThermalFitOptions& o) {
  check_thermal_record(r);
  if (!(o.heater_power_w > 0) || !std::isfinite(o.heater_power_w))
    throw InputError(fmt::format("the heater's power must be positive, not {:g} W", o.heater_power_w));
  const std::size_t total = r.t_s.size();
  std::size_t n = total;
  if (std::isfinite(o.held_out_from_s))
    n = static_cast<std::size_t>(
        std::lower_bound(r.t_s.begin(), r.t_s.end(), r.t_s.front() + o.held_out_from_s - 1e-9) - r.t_s.begin());
  if (n < kMinFittedSamples)
    throw InputError(fmt::format("thermal record: {} samples to fit, fewer than {}", n, kMinFittedSamples));
  ThermalRecord fitted_part;
  const auto cut = [n](const std::vector<double>& v) {
    return v.empty() ? v : std::vector<double>(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n));
  };
  fitted_part = {cut(r.t_s), cut(r.temp_c), cut(r.heater_duty), cut(r.fan_duty), cut(r.feed_mm_s), cut(r.target_c)};
  const bool fan = has_positive(fitted_part.fan_duty), feed = has_positive(fitted_part.feed_mm_s);

  ThermalFit out;
  if (!fan) out.warnings.push_back("the fan did not run in the fitted record: F is held at A (not identified)");
  if (!feed) out.warnings.push_back("no filament was fed in the fitted record: H is held at 0 (not identified)");
  auto p0 = start_values(fitted_part, n, o.heater_power_w, fan, feed);
  double best = std::numeric_limits<double>::infinity();
  for (double rate : kStartSensorRates) {
    auto q = p0;
    q[kR] = rate;
    if (const double s = sum_squares(q, fitted_part, n); s < best) best = s, p0[kR] = rate;
  }
  fitting::LsqOptions lo;
  lo.confidence = o.confidence;
  out.fit = fitting::solve_least_squares("thermal", thermal_problem(fitted_part, n, p0, fan, feed), lo);
  std::array<double, kThermalParams> p{};
  for (std::size_t j = 0; j < kThermalParams; ++j) p[j] = out.fit.params[j].value;
  if (!fan) p[kF] = p[kA], out.fit.params[kF].value = p[kA];
  out.model = model_of(p.data());
  out.fitted_samples = n;
  out.predicted_c = simulate_thermal_record(out.model, p[kStart], r);
  std::vector<double> res(n);
  for (std::size_t i = 0; i < n; ++i) res[i] = out.predicted_c[i] - r.temp_c[i];
  out.variance_factor = fitting::residual_variance_factor(res);
  fitting::inflate_uncertainty(out.fit, out.variance_factor, o.confidence);
  out.correlations = strong_correlations(out.fit);
  if (n < total) {
    double ss = 0;
    for (std::size_t i = n; i < total; ++i)
      ss += (out.predicted_c[i] - r.temp_c[i]) * (out.predicted_c[i] - r.temp_c[i]);
    out.held_out_samples = total - n;
    out.held_out_rms_c = std::sqrt(ss / static_cast<double>(total - n));
    out.held_out_steps = held_out_steps(r, n, out.predicted_c);
  }
  return out;
}

}  // namespace tunekit::ident
