// Delta calibration fit: see delta_calibration.hpp.
#include "tunekit/ident/delta_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::ident {
namespace {

bool delta_factor_supported(int f) {
  return std::find(std::begin(kDeltaFactorChoices), std::end(kDeltaFactorChoices), f) != std::end(kDeltaFactorChoices);
}

double delta_mean_rod(const DeltaGeometry& g) { return (g.rod_mm[0] + g.rod_mm[1] + g.rod_mm[2]) / 3.0; }

// The factors of delta_factor_names, in its order.
enum class DeltaFactorKind { endstop_a, endstop_b, endstop_c, radius, angle_a, angle_b, rod, tilt_x, tilt_y };

std::vector<DeltaFactorKind> delta_factor_kinds(const std::vector<std::string>& names) {
  static const std::pair<const char*, DeltaFactorKind> table[] = {
      {"endstop_a", DeltaFactorKind::endstop_a}, {"endstop_b", DeltaFactorKind::endstop_b},
      {"endstop_c", DeltaFactorKind::endstop_c}, {"delta_radius", DeltaFactorKind::radius},
      {"angle_a", DeltaFactorKind::angle_a},     {"angle_b", DeltaFactorKind::angle_b},
      {"diagonal_rod", DeltaFactorKind::rod},    {"tilt_x", DeltaFactorKind::tilt_x},
      {"tilt_y", DeltaFactorKind::tilt_y}};
  std::vector<DeltaFactorKind> kinds;
  for (const auto& n : names)
    for (const auto& [name, kind] : table)
      if (n == name) kinds.push_back(kind);
  return kinds;
}

// How each factor moves the carriage joints P_t (tower column at the carriage height) and the
// rods under geometry g: the carriage height when homed is H + sqrt(L_t^2 - R^2) + e_t.
class DeltaFactorTerms {
 public:
  explicit DeltaFactorTerms(const DeltaGeometry& g) : radius_(g.radius_mm), rod_(g.rod_mm) {
    for (std::size_t t = 0; t < 3; ++t) {
      const double a = g.angle_deg[t] * std::numbers::pi / 180.0;
      cos_[t] = std::cos(a);
      sin_[t] = std::sin(a);
      rise_[t] = std::sqrt(g.rod_mm[t] * g.rod_mm[t] - g.radius_mm * g.radius_mm);
    }
  }

  // d height / d factor for each of `kinds` (mm per mm, per degree or per percent) into row.
  void height_gradient(const std::vector<DeltaFactorKind>& kinds, const DeltaPoint& q, const DeltaHeightSensitivity& s,
                       double* row) const {
    const auto& w = s.weight;
    const auto& d = s.joint_offset;
    constexpr double deg = std::numbers::pi / 180.0;
    for (std::size_t j = 0; j < kinds.size(); ++j) {
      double v = 0;
      switch (kinds[j]) {
        case DeltaFactorKind::endstop_a:
        case DeltaFactorKind::endstop_b:
        case DeltaFactorKind::endstop_c: {
          const auto t = static_cast<std::size_t>(kinds[j]) - static_cast<std::size_t>(DeltaFactorKind::endstop_a);
          v = w[t] * d[t][2];
          break;
        }
        case DeltaFactorKind::radius:
          for (std::size_t t = 0; t < 3; ++t)
            v += w[t] * (d[t][0] * cos_[t] + d[t][1] * sin_[t] - d[t][2] * radius_ / rise_[t]);
          break;
        case DeltaFactorKind::angle_a:
        case DeltaFactorKind::angle_b: {
          const std::size_t t = kinds[j] == DeltaFactorKind::angle_a ? 0 : 1;
          v = w[t] * deg * radius_ * (-d[t][0] * sin_[t] + d[t][1] * cos_[t]);
          break;
        }
        case DeltaFactorKind::rod:
          for (std::size_t t = 0; t < 3; ++t) v += w[t] * rod_[t] * (d[t][2] / rise_[t] + 1.0);
          break;
        case DeltaFactorKind::tilt_x: v = -q.x / 100.0; break;
        case DeltaFactorKind::tilt_y: v = -q.y / 100.0; break;
      }
      row[j] = v;
    }
  }

 private:
  double radius_;
  std::array<double, 3> rod_, cos_{}, sin_{}, rise_{};
};

}  // namespace

std::vector<std::string> delta_factor_names(int factors) {
  if (!delta_factor_supported(factors))
    throw InputError(fmt::format("{} delta factors: use 3, 4, 6, 7, 8 or 9 (RepRapFirmware's G32 sets)", factors));
  std::vector<std::string> n = {"endstop_a", "endstop_b", "endstop_c"};
  if (factors >= 4) n.push_back("delta_radius");
  if (factors >= 6) n.insert(n.end(), {"angle_a", "angle_b"});
  if (factors == 7 || factors == 9) n.push_back("diagonal_rod");
  if (factors >= 8) n.insert(n.end(), {"tilt_x", "tilt_y"});
  return n;
}

DeltaGeometry delta_apply_factors(const DeltaGeometry& nominal, int factors, const std::vector<double>& v) {
  const auto names = delta_factor_names(factors);
  DeltaGeometry g = nominal;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto& n = names[k];
    if (n == "endstop_a") g.endstop_mm[0] = v[k];
    else if (n == "endstop_b") g.endstop_mm[1] = v[k];
    else if (n == "endstop_c") g.endstop_mm[2] = v[k];
    else if (n == "delta_radius") g.radius_mm = v[k];
    else if (n == "angle_a") g.angle_deg[0] = v[k];
    else if (n == "angle_b") g.angle_deg[1] = v[k];
    else if (n == "diagonal_rod") {
      const double shift = v[k] - delta_mean_rod(nominal);
      for (auto& r : g.rod_mm) r += shift;
    } else if (n == "tilt_x") g.tilt_x = v[k] / 100.0;
    else if (n == "tilt_y") g.tilt_y = v[k] / 100.0;
  }
  return g;
}

DeltaFlatness delta_flatness(const std::vector<double>& h) {
  DeltaFlatness f;
  if (h.empty()) return f;
  double s = 0, s2 = 0;
  for (double v : h) {
    s += v;
    s2 += v * v;
  }
  const double n = static_cast<double>(h.size());
  const double mean = s / n;
  f.rms_mm = std::sqrt(s2 / n);
  double ss = 0;
  for (double v : h) ss += (v - mean) * (v - mean);
  f.std_mm = std::sqrt(ss / n);
  const auto [lo, hi] = std::minmax_element(h.begin(), h.end());
  f.peak_to_peak_mm = *hi - *lo;
  return f;
}

DeltaCalibration fit_delta_calibration(const DeltaGeometry& nominal, const std::vector<DeltaProbe>& probes,
                                       int factors) {
  const auto names = delta_factor_names(factors);
  const std::size_t k = names.size();
  if (probes.size() < k + 1)
    throw InputError(fmt::format("{} probe points for a {}-factor delta calibration: need at least {}", probes.size(),
                                 factors, k + 1));
  // The carriages' travel below their endstops at each probe, under the firmware's (nominal)
  // geometry: the same for every trial geometry, so computed once (as delta_true_height does).
  const auto homed_nominal = delta_homed_carriages(nominal);
  std::vector<std::array<double, 3>> travel(probes.size());
  for (std::size_t i = 0; i < probes.size(); ++i) {
    const auto& p = probes[i];
    double h = 0;
    std::array<double, 3> c{};
    if (!delta_true_height(nominal, nominal, p, h) || !delta_carriages(nominal, {p.x_mm, p.y_mm, p.z_mm}, c))
      throw InputError(fmt::format("probe point ({:g}, {:g}) mm is out of the nominal delta's reach", p.x_mm, p.y_mm));
    for (std::size_t t = 0; t < 3; ++t) travel[i][t] = homed_nominal[t] - c[t];
  }
  fitting::LsqProblem prob;
  for (const auto& n : names) {
    fitting::ParamSpec s;
    s.name = n;
    if (n.starts_with("endstop")) {
      s.unit = "mm";
      s.start = nominal.endstop_mm[static_cast<std::size_t>(n.back() - 'a')];
    } else if (n == "delta_radius") {
      s.unit = "mm";
      s.start = nominal.radius_mm;
      s.lower = 0.5 * nominal.radius_mm;
      s.upper = 1.5 * nominal.radius_mm;
    } else if (n.starts_with("angle")) {
      s.unit = "deg";
      s.start = nominal.angle_deg[static_cast<std::size_t>(n.back() - 'a')];
    } else if (n == "diagonal_rod") {
      s.unit = "mm";
      s.start = delta_mean_rod(nominal);
    } else {
      s.unit = "%";
      s.start = 100.0 * (n == "tilt_x" ? nominal.tilt_x : nominal.tilt_y);
    }
    prob.params.push_back(s);
  }
  const int m = static_cast<int>(probes.size());
  prob.num_residuals = m;
  prob.residuals_are_time_ordered = false;
  for (const auto& p : probes) prob.observed.push_back(p.z_mm);
  auto eval = [&nominal, &travel, factors, kinds = delta_factor_kinds(names), k](const std::vector<double>& v,
                                                                                 double* r, double* jac) {
    const DeltaGeometry g = delta_apply_factors(nominal, factors, v);
    const auto homed = delta_homed_carriages(g);
    const DeltaForward forward(g);
    const DeltaFactorTerms terms(g);
    DeltaHeightSensitivity sens;
    for (std::size_t i = 0; i < travel.size(); ++i) {
      const std::array<double, 3> real{homed[0] - travel[i][0], homed[1] - travel[i][1], homed[2] - travel[i][2]};
      DeltaPoint q;
      if (!forward.position(real, q, jac != nullptr ? &sens : nullptr)) return false;
      r[i] = q.z;
      if (jac != nullptr) terms.height_gradient(kinds, q, sens, jac + i * k);
    }
    return true;
  };
  // The Jacobian is analytic: each factor moves the carriage joints, the rods or the tilt, and
  // DeltaHeightSensitivity turns that into the height's derivative.
  prob.residuals_and_jacobian = [&eval, k](const double* p, double* r, double* jac) {
    return eval(std::vector<double>(p, p + k), r, jac);
  };
  prob.same_residuals_with_jacobian = true;
  DeltaCalibration out;
  out.nominal = nominal;
  out.fit = fitting::solve_least_squares(fmt::format("delta_{}_factor", factors), prob);
  std::vector<double> v;
  for (const auto& q : out.fit.params) v.push_back(q.value);
  out.fitted = delta_apply_factors(nominal, factors, v);
  out.residual_mm.resize(probes.size());
  if (!eval(v, out.residual_mm.data(), nullptr))
    throw FitError("the fitted delta geometry cannot reach every probe point");
  std::vector<double> before;
  for (const auto& p : probes) before.push_back(p.z_mm);
  out.before = delta_flatness(before);
  out.after = delta_flatness(out.residual_mm);
  return out;
}

}  // namespace tunekit::ident
