#include "tunekit/fitting/nozzle_pressure.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/global_start.hpp"

namespace tunekit::fitting {

using std::numbers::pi;

void validate(const NozzleGeometry& g) {
  auto pos = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v)) throw InputError(std::string("nozzle geometry: ") + what + " must be positive");
  };
  pos(g.d_m, "the nozzle diameter d");
  pos(g.l_m, "the land length l");
  pos(g.D_m, "the entrance diameter D");
  pos(g.melt_length_m, "the melt room length");
  if (!(g.cone_half_angle_rad > 0 && g.cone_half_angle_rad < pi / 2))
    throw InputError("nozzle geometry: the cone half angle must be between 0 and 90 degrees");
  if (g.d_m >= g.D_m) throw InputError("nozzle geometry: the nozzle diameter d must be smaller than the entrance D");
}

std::string to_string(PressureModel m) {
  switch (m) {
    case PressureModel::hagen_poiseuille: return "hagen-poiseuille";
    case PressureModel::power_law_capillary: return "power-law";
    case PressureModel::bellini: return "bellini";
    case PressureModel::boles: return "boles";
  }
  return "?";
}

PressureModel parse_pressure_model(std::string_view name) {
  std::string s;
  for (char c : name) s.push_back(c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  for (auto m : {PressureModel::hagen_poiseuille, PressureModel::power_law_capillary, PressureModel::bellini,
                 PressureModel::boles})
    if (s == to_string(m)) return m;
  throw InputError("unknown pressure-drop model '" + std::string(name) +
                   "' (known: hagen-poiseuille, power-law, bellini, boles)");
}

double apparent_wall_shear_rate(double Q, double d) { return 32.0 * Q / (pi * d * d * d); }

double wall_shear_rate(double n, double Q, double d) { return (3 * n + 1) / (4 * n) * apparent_wall_shear_rate(Q, d); }

double hagen_poiseuille_dp(double mu, double Q, const NozzleGeometry& g) {
  return 128.0 * mu * g.l_m * Q / (pi * std::pow(g.d_m, 4));
}

double power_law_capillary_dp(double K, double n, double Q, const NozzleGeometry& g) {
  return 4.0 * g.l_m / g.d_m * K * std::pow(wall_shear_rate(n, Q, g.d_m), n);
}

double bellini_dp(double K, double n, double Q, const NozzleGeometry& g) {
  const double m = 1.0 / n;
  const double phi = std::pow(K, -1.0 / n);
  const double v = 4.0 * Q / (pi * g.D_m * g.D_m);
  const double r1 = g.D_m / 2, r2 = g.d_m / 2;
  const double vp = std::pow(v / phi, 1.0 / m);
  const double beta = 2 * g.cone_half_angle_rad;
  const double dp1 = 2 * g.melt_length_m * vp * std::pow((m + 3) / std::pow(r1, m + 1), 1.0 / m);
  const double dp2 = 2 * m / (3 * std::tan(beta / 2)) * (std::pow(g.d_m, -3.0 / m) - std::pow(g.D_m, -3.0 / m)) * vp *
                     std::pow(r1 * r1 * (m + 3) * std::pow(2.0, m + 3), 1.0 / m);
  const double dp3 = 2 * g.l_m * vp * std::pow((m + 3) * r1 * r1 / std::pow(r2, m + 3), 1.0 / m);
  return dp1 + dp2 + dp3;
}

double boles_entrance_term(double n) { return 1.18 / std::pow(n, 0.7); }

double boles_cone_term(double n, double a) {
  const double s = std::sin(a), c = std::cos(a);
  return 2.0 / (3 * n * s) * std::pow(3 * s / (4 * n * (1 - c) * (1 - c) * (1 + 2 * c)), n);
}

double boles_dp(double K, double n, double Q, const NozzleGeometry& g) {
  return K * std::pow(wall_shear_rate(n, Q, g.d_m), n) *
         (boles_entrance_term(n) + 4 * g.l_m / g.d_m + boles_cone_term(n, g.cone_half_angle_rad));
}

double pressure_drop(PressureModel m, double K, double n, double Q, const NozzleGeometry& g) {
  switch (m) {
    case PressureModel::hagen_poiseuille: return hagen_poiseuille_dp(K, Q, g);
    case PressureModel::power_law_capillary: return power_law_capillary_dp(K, n, Q, g);
    case PressureModel::bellini: return bellini_dp(K, n, Q, g);
    case PressureModel::boles: return boles_dp(K, n, Q, g);
  }
  return 0;
}

double pressure_drop_slope(PressureModel m, double K, double n, double Q, const NozzleGeometry& g) {
  const double dp = pressure_drop(m, K, n, Q, g);
  return m == PressureModel::hagen_poiseuille ? dp / Q : n * dp / Q;
}

LocalPowerLaw local_power_law(const ViscositySpec& v, double Q, double d, double T, double p) {
  const double ga = apparent_wall_shear_rate(Q, d);
  double n = std::clamp(v.local_flow_index(ga, T, p), 0.05, 1.0);
  double gw = ga;
  for (int it = 0; it < 30; ++it) {
    gw = wall_shear_rate(n, Q, d);
    const double n_new = std::clamp(v.local_flow_index(gw, T, p), 0.05, 1.0);
    if (std::abs(n_new - n) < 1e-12) {
      n = n_new;
      break;
    }
    n = n_new;
  }
  gw = wall_shear_rate(n, Q, d);
  LocalPowerLaw r;
  r.n = n;
  r.wall_shear_rate_1_s = gw;
  r.K_Pa_s_n = v.viscosity(gw, T, p) * std::pow(gw, 1.0 - n);
  return r;
}

double pressure_drop(PressureModel m, const ViscositySpec& v, double Q, double T, const NozzleGeometry& g) {
  if (m == PressureModel::hagen_poiseuille)
    return hagen_poiseuille_dp(v.viscosity(apparent_wall_shear_rate(Q, g.d_m), T), Q, g);
  const auto lp = local_power_law(v, Q, g.d_m, T);
  return pressure_drop(m, lp.K_Pa_s_n, lp.n, Q, g);
}

double pressure_drop_slope(PressureModel m, const ViscositySpec& v, double Q, double T, const NozzleGeometry& g) {
  const double h = 1e-4 * Q;
  return (pressure_drop(m, v, Q + h, T, g) - pressure_drop(m, v, Q - h, T, g)) / (2 * h);
}

PowerLawCoefficients holtrup_peek_power_law(double T) {
  return {std::pow(10.0, 20.14448225350382) * std::pow(T, -6.2288201451850265),
          0.17651020236319326 + T * 0.0008956157030695386};
}

namespace {

// A drop at the consistency 1 and this flow, times K (Q / Q_ref)^n, is the drop at K and Q.
constexpr double kNozzleReferenceFlow_m3_s = 1e-9;

// Where the nozzle fit's parameters sit in its vector (-1: not fitted). ln K (or ln mu) is first.
struct NozzleLayout {
  int n = -1, Ea = -1, T_ref = -1;
};

// ln dP(1, n, Q_ref) and its derivative in n (fourth-order central differences: it is one
// function of n, the same for every row). NaN when the model has no finite drop there.
std::pair<double, double> ln_unit_drop(PressureModel model, double n, const NozzleGeometry& g, bool slope) {
  const auto f = [&](double x) { return std::log(pressure_drop(model, 1.0, x, kNozzleReferenceFlow_m3_s, g)); };
  const double v = f(n);
  if (!slope || !std::isfinite(v)) return {v, 0.0};
  const double h = 1e-4 * std::max(1.0, std::abs(n));
  return {v, (8 * (f(n + h) - f(n - h)) - (f(n + 2 * h) - f(n - 2 * h))) / (12 * h)};
}

// Residuals ln dP_model - ln dP_measured of the rows idx, and their Jacobian when J is not null.
// Every model's drop is homogeneous in K and the flow: dP(K, n, Q) = K (Q / Q_ref)^n dP(1, n,
// Q_ref) (the power law's shear stress scales so; Hagen-Poiseuille is n = 1), so
// ln dP = ln K + ln a_T + n ln(Q / Q_ref) + ln dP(1, n, Q_ref) costs arithmetic per row.
bool nozzle_residuals(PressureModel model, const NozzleGeometry& g, const NozzleLayout& at, std::size_t np,
                      const double* p, const std::vector<std::size_t>& idx, const std::vector<double>& ln_flow,
                      const std::vector<double>& T, const std::vector<double>& ln_obs, double* r, double* J) {
  const double n = at.n >= 0 ? p[at.n] : 1.0;
  const auto [c, dc] = ln_unit_drop(model, n, g, J != nullptr && at.n >= 0);
  if (!std::isfinite(c) || !std::isfinite(dc)) return false;
  const double Ea = at.Ea >= 0 ? p[at.Ea] : 0.0, T_ref = at.T_ref >= 0 ? p[at.T_ref] : 1.0;
  for (std::size_t k = 0; k < idx.size(); ++k) {
    const std::size_t i = idx[k];
    const double w = at.Ea >= 0 ? (1.0 / T[i] - 1.0 / T_ref) / kGasConstant : 0.0;  // d ln a_T / d Ea
    r[k] = p[0] + Ea * w + n * ln_flow[i] + c - ln_obs[i];
    if (!std::isfinite(r[k])) return false;
    if (J == nullptr) continue;
    double* row = J + k * np;
    row[0] = 1.0;
    if (at.n >= 0) row[at.n] = ln_flow[i] + dc;
    if (at.Ea >= 0) row[at.Ea] = w;
    if (at.T_ref >= 0) row[at.T_ref] = Ea / (kGasConstant * T_ref * T_ref);
  }
  return true;
}

}  // namespace

FitResult fit_nozzle_rheology(const NozzleFlowData& d, PressureModel model, const NozzleGeometry& g, double T_ref_K) {
  validate(g);
  const std::size_t n = d.flow_m3_s.size();
  if (d.pressure_Pa.size() != n || d.temperature_K.size() != n)
    throw InputError("nozzle data columns differ in length");
  std::vector<double> levels;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(d.flow_m3_s[i] > 0)) throw InputError("point " + std::to_string(i + 1) + ": flows must be positive");
    if (!(d.pressure_Pa[i] > 0)) throw InputError("point " + std::to_string(i + 1) + ": pressures must be positive");
    if (!(d.temperature_K[i] > 0))
      throw InputError("point " + std::to_string(i + 1) + ": temperatures must be positive (K)");
  }
  // Temperature levels (within 0.05 K of each other), sorted: linear after the sort, so many
  // distinct temperatures do not make this quadratic.
  std::vector<double> sorted_T = d.temperature_K;
  std::sort(sorted_T.begin(), sorted_T.end());
  for (double T : sorted_T)
    if (levels.empty() || T - levels.back() > 0.05) levels.push_back(T);
  const bool newtonian = model == PressureModel::hagen_poiseuille;
  const bool shifted = levels.size() > 1;
  const double T_ref = std::isfinite(T_ref_K) ? T_ref_K : (levels.empty() ? 0.0 : levels[(levels.size() - 1) / 2]);
  const double inf = std::numeric_limits<double>::infinity();
  LsqProblem prob;
  // ln K (or ln mu) is estimated; exp-transformed below.
  prob.params.push_back({newtonian ? "mu_Pa_s" : "K_Pa_s_n", newtonian ? "Pa.s" : "Pa.s^n", std::log(1e3),
                         std::log(1e-2), std::log(1e9)});
  if (!newtonian) prob.params.push_back({"n", "1", 0.5, 0.05, 1.0});
  if (shifted) {
    prob.params.push_back({"Ea_J_per_mol", "J/mol", 1e5, 1e3, 1e6});
    prob.params.push_back({"T_ref_K", "K", T_ref, -inf, inf, true});
  }
  const int k = static_cast<int>(prob.params.size()) - (shifted ? 1 : 0);
  if (static_cast<int>(n) <= k)
    throw InputError(std::to_string(n) + " nozzle measurements for " + std::to_string(k) +
                     " free parameters; need more measurements than parameters");
  prob.num_residuals = static_cast<int>(n);
  prob.residuals_are_time_ordered = false;
  std::vector<double> ln_obs(n), ln_flow(n);
  for (std::size_t i = 0; i < n; ++i) {
    ln_obs[i] = std::log(d.pressure_Pa[i]);
    ln_flow[i] = std::log(d.flow_m3_s[i] / kNozzleReferenceFlow_m3_s);
  }
  prob.observed = ln_obs;
  const NozzleLayout at{newtonian ? -1 : 1, shifted ? (newtonian ? 1 : 2) : -1, shifted ? (newtonian ? 2 : 3) : -1};
  // Residuals of the rows `idx`: every row for the fit, an evenly strided subset for the start
  // search (which only has to find the basin; the final least squares sees every row).
  const auto residuals_of = [&, np = prob.params.size()](const std::vector<std::size_t>& idx) {
    return [&, np, idx](const double* p, double* r, double* J) {
      return nozzle_residuals(model, g, at, np, p, idx, ln_flow, d.temperature_K, ln_obs, r, J);
    };
  };
  std::vector<std::size_t> all(n), sub;
  for (std::size_t i = 0; i < n; ++i) all[i] = i;
  constexpr std::size_t kMaxSearch = 240;
  if (n > kMaxSearch)
    for (std::size_t k = 0; k < kMaxSearch; ++k) sub.push_back(k * n / kMaxSearch);
  else sub = all;
  prob.residuals_and_jacobian = residuals_of(all);
  prob.same_residuals_with_jacobian = true;
  LsqProblem search = prob;
  search.num_residuals = static_cast<int>(sub.size());
  search.observed.clear();
  for (std::size_t i : sub) search.observed.push_back(ln_obs[i]);
  search.residuals_and_jacobian = residuals_of(sub);
  std::string name = "nozzle-" + to_string(model) + (newtonian ? "/newtonian" : "/power-law");
  if (shifted) name += "+arrhenius";
  auto fit = solve_with_global_start(name, prob, {}, {}, &search);
  auto& p0 = fit.params[0];
  p0.value = std::exp(p0.value);
  p0.std_error *= p0.value;
  p0.ci95_lo = std::exp(p0.ci95_lo);
  p0.ci95_hi = std::exp(p0.ci95_hi);
  for (auto& w : fit.warnings)
    if (w.rfind(p0.name, 0) == 0) w = p0.name + " ended on its bound; the data do not determine it well";
  return fit;
}

}  // namespace tunekit::fitting
