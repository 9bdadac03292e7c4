// The viscosity models in logarithms with their gradients: the residuals and analytic Jacobians
// of the viscosity fits (rheology_fit.cpp) and of the master curve (rheology_superposition.cpp).
// They restate viscosity.hpp's definitions in ln eta; a test holds them to those.
#include <cmath>
#include <utility>

#include "rheology_fit_detail.hpp"

namespace tunekit::fitting::rheology_detail {
namespace {

// ln(1 + e^z) and its derivative e^z / (1 + e^z); NaN where e^z overflows (the power in the
// model's own form overflows there too: outside the arithmetic's range, the solver backs off).
std::pair<double, double> softplus(double z) {
  const double e = std::exp(z);
  if (!std::isfinite(e)) return {kNaN, kNaN};
  return {std::log1p(e), e / (1.0 + e)};
}

// ln a_T of the shift whose parameters start at s, and its gradient in them into d.
double ln_shift(TemperatureShift shift, const double* s, double T, double* d) {
  if (shift == TemperatureShift::arrhenius) {  // a_T = exp((Ea / R) (1/T - 1/T_ref))
    const double Ea = s[0], T_ref = s[1], w = (1.0 / T - 1.0 / T_ref) / kGasConstant;
    if (d != nullptr) d[0] = w, d[1] = Ea / (kGasConstant * T_ref * T_ref);
    return Ea * w;
  }
  if (shift == TemperatureShift::wlf) {  // a_T = exp(-C1 (T - T_ref) / (C2 + T - T_ref))
    const double C1 = s[0], C2 = s[1], x = T - s[2], den = C2 + x;
    if (d != nullptr) d[0] = -x / den, d[1] = C1 * x / (den * den), d[2] = C1 * C2 / (den * den);
    return -C1 * x / den;
  }
  return 0.0;
}

// Carreau-Yasuda at ln a_T = A: eta = a_T (eta_inf + (eta0 - eta_inf) (1 + (lambda a_T g)^a)^((n-1)/a)),
// p = ln eta0, eta_inf, ln lambda, a, n; dA (if d) is d ln eta / dA.
bool ln_carreau_yasuda(const double* p, double ln_g, double A, double& ln_eta, double* d, double& dA) {
  const double eta0 = std::exp(p[0]), eta_inf = p[1], a = p[3], n = p[4];
  const double z = a * (p[2] + A + ln_g), e = (n - 1.0) / a;
  const auto [ln_b, sig] = softplus(z);
  const double P = std::exp(e * ln_b);
  const double q = eta_inf + (eta0 - eta_inf) * P;
  if (!(q > 0)) return false;
  ln_eta = A + (eta_inf == 0 ? p[0] + e * ln_b : std::log(q));
  if (d != nullptr) {
    const double span = (eta0 - eta_inf) / q, dP_dz = P * e * sig;
    d[0] = eta0 * P / q;
    d[1] = (1.0 - P) / q;
    d[2] = span * dP_dz * a;
    d[3] = span * P * (n - 1.0) / (a * a) * (sig * z - ln_b);
    d[4] = span * P * ln_b / a;
    dA = 1.0 + span * dP_dz * a;
  }
  return true;
}

// Cross-WLF, p = n, ln tau*, ln D1, D2, D3, A1, A2 (no separate shift).
double ln_cross_wlf(const double* p, double ln_g, double T, double pr, double* d) {
  const double n = p[0], ln_ts = p[1], ln_d1 = p[2], D2 = p[3], D3 = p[4], A1 = p[5], A2 = p[6];
  const double x = T - D2 - D3 * pr, den = A2 + D3 * pr + x;
  if (!(den > 0)) return kNaN;
  double c[3];
  const double ln_eta = ln_cross_viscosity(ln_d1 - A1 * x / den, ln_g, ln_ts, n, d != nullptr ? c : nullptr);
  if (d != nullptr) {
    d[0] = c[2];
    d[1] = c[1];
    d[2] = c[0];
    d[3] = c[0] * A1 * (A2 + D3 * pr) / (den * den);
    d[4] = c[0] * A1 * pr / den;
    d[5] = c[0] * (-x / den);
    d[6] = c[0] * A1 * x / (den * den);
  }
  return ln_eta;
}

}  // namespace

double ln_cross_viscosity(double ln_eta0, double ln_g, double ln_tau_star, double n, double* d) {
  const double L = ln_eta0 + ln_g - ln_tau_star;
  const auto [sp, s] = softplus((1.0 - n) * L);
  if (d != nullptr) {
    d[0] = 1.0 - (1.0 - n) * s;
    d[1] = (1.0 - n) * s;
    d[2] = s * L;
  }
  return ln_eta0 - sp;
}

LnViscosity::LnViscosity(ViscosityModel model, TemperatureShift shift)
    : model_(model), shift_(model == ViscosityModel::cross_wlf ? TemperatureShift::none : shift) {
  offset_ = viscosity_param_names(model).size();
  size_ = offset_ + shift_param_names(shift_).size() + (shift_ == TemperatureShift::none ? 0 : 1);
}

bool LnViscosity::operator()(const double* p, double ln_g, double T, double pressure, double& ln_eta, double* d) const {
  if (model_ == ViscosityModel::cross_wlf) {
    ln_eta = ln_cross_wlf(p, ln_g, T, pressure, d);
    return std::isfinite(ln_eta);
  }
  double* ds = d != nullptr ? d + offset_ : nullptr;
  const double A = ln_shift(shift_, p + offset_, T, ds);
  double dA = 1.0;  // d ln eta / d ln a_T
  switch (model_) {
    case ViscosityModel::newtonian:
      ln_eta = p[0] + A;
      if (d != nullptr) d[0] = 1.0;
      break;
    case ViscosityModel::power_law:
      ln_eta = p[0] + A + (p[1] - 1.0) * ln_g;
      if (d != nullptr) d[0] = 1.0, d[1] = ln_g;
      break;
    case ViscosityModel::cross:
      ln_eta = ln_cross_viscosity(p[0] + A, ln_g, p[1], p[2], d);
      if (d != nullptr) dA = d[0];
      break;
    case ViscosityModel::carreau_yasuda:
      if (!ln_carreau_yasuda(p, ln_g, A, ln_eta, d, dA)) return false;
      break;
    case ViscosityModel::cross_wlf: break;
  }
  if (ds != nullptr)
    for (std::size_t j = offset_; j < size_; ++j) d[j] *= dA;
  return std::isfinite(ln_eta);
}

ViscosityRows viscosity_rows(const RheologyData& data) {
  ViscosityRows r;
  const std::size_t n = data.size();
  for (std::size_t i = 0; i < n; ++i) {
    r.ln_g.push_back(std::log(data.shear_rate_1_s[i]));
    r.ln_obs.push_back(std::log(data.viscosity_Pa_s[i]));
    r.sw.push_back(data.weight.empty() ? 1.0 : std::sqrt(data.weight[i]));
    r.pressure.push_back(data.pressure_Pa.empty() ? 0.0 : data.pressure_Pa[i]);
  }
  r.T = data.temperature_K;
  return r;
}

LsqProblem viscosity_problem(LsqProblem base, const ViscosityRows& rows, std::vector<std::size_t> idx,
                             const LnViscosity& ln_eta) {
  base.num_residuals = static_cast<int>(idx.size());
  base.observed.clear();
  for (auto i : idx) base.observed.push_back(rows.ln_obs[i]);
  const std::size_t np = base.params.size();
  base.residuals = nullptr;
  base.same_residuals_with_jacobian = true;
  base.residuals_and_jacobian = [&rows, idx = std::move(idx), ln_eta, np](const double* p, double* r, double* J) {
    for (std::size_t k = 0; k < idx.size(); ++k) {
      const auto i = idx[k];
      double* row = J != nullptr ? J + np * k : nullptr;
      double v = 0;
      if (!ln_eta(p, rows.ln_g[i], rows.T[i], rows.pressure[i], v, row)) return false;
      const double w = rows.sw[i];
      r[k] = w * (v - rows.ln_obs[i]);
      if (row != nullptr)
        for (std::size_t j = 0; j < np; ++j) row[j] *= w;
    }
    return true;
  };
  return base;
}

}  // namespace tunekit::fitting::rheology_detail
