#include "tunekit/ident/bed_mass.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::ident {
namespace {

constexpr double kNewtonPerMmToPerM = 1000;  // k in N/mm, the model in SI

double model_freq(double m0_kg, double k_N_per_mm, double added_kg) {
  return std::sqrt(k_N_per_mm * kNewtonPerMmToPerM / (m0_kg + added_kg)) / (2 * std::numbers::pi);
}

/// d f / d m0 and d f / d k at an added mass.
std::array<double, 2> freq_gradient(double m0, double k, double added_kg) {
  const double f = model_freq(m0, k, added_kg);
  return {-f / (2 * (m0 + added_kg)), f / (2 * k)};
}

void check_points(const std::vector<BedMassPoint>& points) {
  if (points.size() < 2) throw InputError("the bed's mass model needs sweeps at two or more masses");
  for (const auto& p : points) {
    if (!(p.freq_hz > 0) || !(p.freq_stderr_hz > 0))
      throw InputError(fmt::format("{}: the sweep gave no frequency with a standard error", p.source));
    if (!(p.added_mass_kg >= 0) || !std::isfinite(p.added_mass_kg))
      throw InputError(fmt::format("{}: the added mass must be zero or positive", p.source));
  }
  const auto [lo, hi] = std::minmax_element(
      points.begin(), points.end(), [](const auto& a, const auto& b) { return a.added_mass_kg < b.added_mass_kg; });
  if (hi->added_mass_kg - lo->added_mass_kg <= 0)
    throw InputError("the bed's mass model needs sweeps at two or more different masses");
  if (!(hi->freq_hz < lo->freq_hz))
    throw InputError(fmt::format(
        "the frequency does not fall as the mass grows ({:.3f} Hz at {:g} kg, {:.3f} Hz at {:g} kg): the swept "
        "mode is not the bed's, or the masses were not on the bed",
        lo->freq_hz, lo->added_mass_kg, hi->freq_hz, hi->added_mass_kg));
}

/// Start values from the straight line 1/f^2 = 4 pi^2 (m0 + m) / k (least squares).
std::array<double, 2> start_values(const std::vector<BedMassPoint>& points) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(points.size());
  for (const auto& p : points) {
    const double y = 1 / (p.freq_hz * p.freq_hz);
    sx += p.added_mass_kg, sy += y, sxx += p.added_mass_kg * p.added_mass_kg, sxy += p.added_mass_kg * y;
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icpt = (sy - slope * sx) / n;
  const double k_si = 4 * std::numbers::pi * std::numbers::pi / slope;
  return {std::max(icpt / slope, 1e-3), k_si / kNewtonPerMmToPerM};
}

/// The covariance (J^T J)^-1 of the weighted residuals at the solution, widened by the reduced
/// chi-square when the sweeps scatter more than their errors say.
std::array<double, 4> covariance(const std::vector<BedMassPoint>& points, double m0, double k, double scale) {
  double a = 0, b = 0, c = 0;
  for (const auto& p : points) {
    const auto g = freq_gradient(m0, k, p.added_mass_kg);
    const double w = 1 / (p.freq_stderr_hz * p.freq_stderr_hz);
    a += w * g[0] * g[0], b += w * g[0] * g[1], c += w * g[1] * g[1];
  }
  const double det = a * c - b * b;
  if (!(det > 0)) throw FitError("bed mass model: the masses do not separate the moving mass from the stiffness");
  return {scale * c / det, -scale * b / det, -scale * b / det, scale * a / det};
}

BedDampingTrend damping_trend(const std::vector<BedMassPoint>& points, const BedMassModel& model) {
  BedDampingTrend t;
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, cw = 0, cs = 0;
  for (const auto& p : points) {
    const double c =
        2 * p.zeta *
        std::sqrt(model.stiffness_N_per_mm * kNewtonPerMmToPerM * (model.moving_mass_kg + p.added_mass_kg));
    t.damping_N_s_per_m.push_back(c);
    if (!(p.zeta_stderr > 0) || !std::isfinite(p.zeta)) continue;
    const double w = 1 / (p.zeta_stderr * p.zeta_stderr);
    sw += w, sx += w * p.added_mass_kg, sy += w * p.zeta;
    sxx += w * p.added_mass_kg * p.added_mass_kg, sxy += w * p.added_mass_kg * p.zeta;
    cw += w, cs += w * c;
  }
  const double det = sw * sxx - sx * sx;
  if (!(det > 0)) return t;
  t.slope_per_kg = (sw * sxy - sx * sy) / det;
  t.zeta0 = (sy - t.slope_per_kg * sx) / sw;
  t.slope_stderr_per_kg = std::sqrt(sw / det);
  t.slope_ci95_lo = t.slope_per_kg - fitting::kZ95 * t.slope_stderr_per_kg;
  t.slope_ci95_hi = t.slope_per_kg + fitting::kZ95 * t.slope_stderr_per_kg;
  t.mean_damping_N_s_per_m = cs / cw;
  return t;
}

void set_interval(fitting::Param& p, double variance) {
  p.std_error = std::sqrt(variance);
  p.ci95_lo = p.value - fitting::kZ95 * p.std_error;
  p.ci95_hi = p.value + fitting::kZ95 * p.std_error;
  p.ci95_method = "wald";
}

}  // namespace

double BedMassModel::freq_hz(double added_kg) const { return model_freq(moving_mass_kg, stiffness_N_per_mm, added_kg); }

double BedMassModel::added_mass_at(double f_hz) const {
  const double w = 2 * std::numbers::pi * f_hz;
  return stiffness_N_per_mm * kNewtonPerMmToPerM / (w * w) - moving_mass_kg;
}

BedFrequencyPrediction BedMassModel::predict(double added_kg) const {
  BedFrequencyPrediction p;
  p.added_mass_kg = added_kg;
  p.freq_hz = freq_hz(added_kg);
  const auto g = freq_gradient(moving_mass_kg, stiffness_N_per_mm, added_kg);
  const double var = g[0] * g[0] * covariance[0] + 2 * g[0] * g[1] * covariance[1] + g[1] * g[1] * covariance[3];
  p.stderr_hz = std::sqrt(std::max(var, 0.0));
  p.ci95_lo_hz = p.freq_hz - fitting::kZ95 * p.stderr_hz;
  p.ci95_hi_hz = p.freq_hz + fitting::kZ95 * p.stderr_hz;
  return p;
}

double BedMassModel::correlation() const {
  const double d = std::sqrt(covariance[0] * covariance[3]);
  return d > 0 ? std::clamp(covariance[1] / d, -1.0, 1.0) : fitting::kNaN;
}

BedMassFit fit_bed_mass(const std::vector<BedMassPoint>& points) {
  check_points(points);
  const auto start = start_values(points);
  fitting::LsqProblem prob;
  prob.params = {{"moving_mass_kg", "kg", start[0], 1e-6, 1e4}, {"stiffness_N_per_mm", "N/mm", start[1], 1e-9, 1e9}};
  prob.num_residuals = static_cast<int>(points.size());
  prob.residuals = [&points](const double* p, double* r) {
    for (std::size_t i = 0; i < points.size(); ++i)
      r[i] = (model_freq(p[0], p[1], points[i].added_mass_kg) - points[i].freq_hz) / points[i].freq_stderr_hz;
    return true;
  };
  prob.residuals_are_time_ordered = false;
  fitting::LsqOptions opt;
  opt.absolute_sigma = true;
  opt.compute_covariance = false;  // from the sweeps' own errors below, also with two sweeps
  BedMassFit out;
  out.points = points;
  out.fit = fitting::solve_least_squares("bed_mass", prob, opt);
  BedMassModel& m = out.model;
  m.moving_mass_kg = out.fit.value("moving_mass_kg");
  m.stiffness_N_per_mm = out.fit.value("stiffness_N_per_mm");
  out.dof = static_cast<int>(points.size()) - 2;
  out.chi_square = out.fit.diagnostics.rss;
  const double reduced = out.dof > 0 ? out.chi_square / out.dof : 0.0;
  if (reduced > 1)
    out.warnings.push_back(fmt::format(
        "the sweeps scatter {:.2g} times more than their errors say about f(m) (reduced chi-square): the intervals "
        "are widened by it",
        reduced));
  m.covariance = covariance(points, m.moving_mass_kg, m.stiffness_N_per_mm, std::max(1.0, reduced));
  out.fit.covariance = {m.covariance.begin(), m.covariance.end()};
  set_interval(out.fit.params[0], m.covariance[0]);
  set_interval(out.fit.params[1], m.covariance[3]);
  out.damping = damping_trend(points, m);
  return out;
}

BedHeldOutCheck check_held_out(const BedMassModel& model, const BedMassPoint& point) {
  BedHeldOutCheck c;
  c.point = point;
  c.predicted = model.predict(point.added_mass_kg);
  c.error_hz = point.freq_hz - c.predicted.freq_hz;
  c.relative_error = c.error_hz / c.predicted.freq_hz;
  const double s2 = c.predicted.stderr_hz * c.predicted.stderr_hz +
                    (point.freq_stderr_hz > 0 ? point.freq_stderr_hz * point.freq_stderr_hz : 0.0);
  c.z = s2 > 0 ? c.error_hz / std::sqrt(s2) : fitting::kNaN;
  return c;
}

}  // namespace tunekit::ident
