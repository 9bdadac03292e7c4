#include "tunekit/ident/sine_dwell.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = 180.0 / kPi;

nlohmann::json dwell_param_json(const fitting::Param& p) {
  return {{"value", p.value}, {"stderr", p.std_error}, {"ci95", {p.ci95_lo, p.ci95_hi}}, {"unit", p.unit}};
}

nlohmann::json sine_json(const fitting::FitResult& f) {
  return {{"amplitude", dwell_param_json(f.param("amplitude"))},
          {"phase_deg", dwell_param_json(f.param("phase_deg"))},
          {"offset", dwell_param_json(f.param("offset"))},
          {"model", f.model},
          {"diagnostics", fitting::to_json(f.diagnostics)}};
}

}  // namespace

double wrap_deg(double deg) {
  double w = std::fmod(deg, 360.0);
  if (w <= -180.0) w += 360.0;
  if (w > 180.0) w -= 360.0;
  return w;
}

fitting::FitResult fit_sine(std::span<const double> t, std::span<const double> y, double freq_hz,
                            const std::string& unit) {
  if (!(freq_hz > 0) || !std::isfinite(freq_hz)) throw InputError("sine dwell: the frequency must be positive");
  if (t.size() != y.size()) throw InputError("sine dwell: time and signal have different lengths");
  const std::size_t n = t.size();
  if (n < 4) throw InputError(fmt::format("sine dwell: too few samples ({}); at least 4 are needed", n));
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(y[i])) throw InputError("sine dwell: NaN or infinite sample");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw InputError(fmt::format("sine dwell: time is not increasing at sample {} (t = {} s)", i + 1, t[i]));
  }
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  if (!(*hi > *lo)) throw InputError("sine dwell: the signal is constant; there is no sine to fit");
  const double w = 2 * kPi * freq_hz;
  // Exact linear least squares: y = c + a sin(wt) + b cos(wt).
  Eigen::MatrixXd X(static_cast<Eigen::Index>(n), 3);
  Eigen::VectorXd Y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    X(k, 0) = 1.0;
    X(k, 1) = std::sin(w * t[i]);
    X(k, 2) = std::cos(w * t[i]);
    Y(k) = y[i];
  }
  const Eigen::Vector3d c = fitting::least_squares_solve(X, Y);
  const double A0 = std::hypot(c(1), c(2));
  const double phi0 = std::atan2(c(2), c(1)) * kDeg;  // a sin + b cos = A sin(wt + phi)
  const std::vector<double> tv(t.begin(), t.end()), yv(y.begin(), y.end());
  fitting::LsqProblem prob;
  prob.params = {{"amplitude", unit, A0}, {"phase_deg", "deg", phi0}, {"offset", unit, c(0)}};
  prob.num_residuals = static_cast<int>(n);
  prob.observed = yv;
  prob.residuals_and_jacobian = [tv, yv, w](const double* p, double* r, double* jac) {
    for (std::size_t i = 0; i < tv.size(); ++i) {
      const double arg = w * tv[i] + p[1] / kDeg;
      const double s = std::sin(arg), co = std::cos(arg);
      r[i] = p[2] + p[0] * s - yv[i];
      if (jac != nullptr) {
        jac[3 * i] = s;
        jac[3 * i + 1] = p[0] * co / kDeg;
        jac[3 * i + 2] = 1.0;
      }
    }
    return true;
  };
  auto f =
      fitting::solve_least_squares(fmt::format("sine: offset + amplitude sin(2 pi {:.6g} t + phase)", freq_hz), prob);
  // Normalize to amplitude >= 0 and phase in (-180, 180].
  for (auto& p : f.params) {
    if (p.name == "amplitude" && p.value < 0) {
      p.value = -p.value;
      std::swap(p.ci95_lo, p.ci95_hi);
      p.ci95_lo = -p.ci95_lo;
      p.ci95_hi = -p.ci95_hi;
      for (auto& q : f.params)
        if (q.name == "phase_deg") {
          q.value += 180;
          q.ci95_lo += 180;
          q.ci95_hi += 180;
        }
    }
  }
  for (auto& p : f.params)
    if (p.name == "phase_deg") {
      const double shift = wrap_deg(p.value) - p.value;
      p.value += shift;
      p.ci95_lo += shift;
      p.ci95_hi += shift;
    }
  if (!(f.value("amplitude") > 2 * f.param("amplitude").std_error))
    f.warnings.push_back(
        fmt::format("the amplitude ({:.3g}) is within two standard errors of zero; the phase is "
                    "poorly determined",
                    f.value("amplitude")));
  return f;
}

SineDwell sine_dwell(std::span<const double> t, std::span<const double> y, double freq_hz, std::span<const double> u,
                     const std::string& y_unit, const std::string& u_unit) {
  SineDwell s;
  s.freq_hz = freq_hz;
  s.output = fit_sine(t, y, freq_hz, y_unit);
  if (u.empty()) return s;
  s.input = fit_sine(t, u, freq_hz, u_unit);
  const auto& Ay = s.output.param("amplitude");
  const auto& Au = s.input->param("amplitude");
  const double dof =
      static_cast<double>(s.output.diagnostics.num_observations + s.input->diagnostics.num_observations - 6);
  const double tq = fitting::t_multiplier(0.95, dof);
  s.gain.name = "gain";
  s.gain.unit = y_unit + "/" + u_unit;
  s.gain.value = Ay.value / Au.value;
  s.gain.std_error = std::abs(s.gain.value) * std::hypot(Ay.std_error / Ay.value, Au.std_error / Au.value);
  s.gain.ci95_lo = s.gain.value - tq * s.gain.std_error;
  s.gain.ci95_hi = s.gain.value + tq * s.gain.std_error;
  s.phase_lag_deg.name = "phase_lag_deg";
  s.phase_lag_deg.unit = "deg";
  s.phase_lag_deg.value = wrap_deg(s.input->value("phase_deg") - s.output.value("phase_deg"));
  s.phase_lag_deg.std_error = std::hypot(s.input->param("phase_deg").std_error, s.output.param("phase_deg").std_error);
  s.phase_lag_deg.ci95_lo = s.phase_lag_deg.value - tq * s.phase_lag_deg.std_error;
  s.phase_lag_deg.ci95_hi = s.phase_lag_deg.value + tq * s.phase_lag_deg.std_error;
  return s;
}

nlohmann::json to_json(const SineDwell& s) {
  nlohmann::json j{{"freq_hz", s.freq_hz}, {"output", sine_json(s.output)}};
  if (s.input) {
    j["input"] = sine_json(*s.input);
    j["gain"] = dwell_param_json(s.gain);
    j["phase_lag_deg"] = dwell_param_json(s.phase_lag_deg);
  }
  return j;
}

}  // namespace tunekit::ident
