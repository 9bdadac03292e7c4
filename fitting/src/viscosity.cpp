#include "tunekit/fitting/viscosity.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "tunekit/core/error.hpp"

namespace tunekit::fitting {
namespace {

std::string normalized(std::string_view s) {
  std::string out;
  for (char c : s) out.push_back(c == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return out;
}

}  // namespace

double cross_wlf_zero_shear(const CrossWlfParams& c, double T, double p) {
  const double t_star = c.D2_K + c.D3_K_per_Pa * p;
  const double a2 = c.A2_K + c.D3_K_per_Pa * p;
  return c.D1_Pa_s * std::exp(-c.A1 * (T - t_star) / (a2 + T - t_star));
}

double cross_viscosity(double eta0, double tau_star, double n, double g) {
  return eta0 / (1.0 + std::pow(eta0 * g / tau_star, 1.0 - n));
}

double cross_wlf_viscosity(const CrossWlfParams& c, double g, double T, double p) {
  return cross_viscosity(cross_wlf_zero_shear(c, T, p), c.tau_star_Pa, c.n, g);
}

double power_law_viscosity(double K, double n, double g) { return K * std::pow(g, n - 1.0); }

double carreau_yasuda_viscosity(double eta0, double eta_inf, double lambda, double a, double n, double g) {
  return eta_inf + (eta0 - eta_inf) * std::pow(1.0 + std::pow(lambda * g, a), (n - 1.0) / a);
}

double arrhenius_shift(double T, double Ea, double T_ref) {
  return std::exp(Ea / kGasConstant * (1.0 / T - 1.0 / T_ref));
}

double wlf_shift(double T, double C1, double C2, double T_ref) {
  return std::exp(-C1 * (T - T_ref) / (C2 + T - T_ref));
}

const std::vector<CrossWlfMaterial>& cross_wlf_library() {
  // Holtrup 2019 Table 2.4 (PEEK, ABS) and appendix A initLibrary() (ULTEM 1010, whose temperature
  // range in the code, 343..400, is not in kelvin and is therefore left out).
  static const std::vector<CrossWlfMaterial> lib{
      {"PEEK", {0.4266, 124139, 2.89808e16, 403.15, 0, 36.041, 51.6}, 643, 723},
      {"ABS", {0.2353, 72350, 2.2149e12, 378.15, 0, 28.8, 51.6}, 463, 513},
      {"ULTEM1010", {0.1134, 830200, 2.16e13, 473.1, 0, 31.81, 51.6}, 0, 0},
  };
  return lib;
}

const CrossWlfMaterial& cross_wlf_material(std::string_view name) {
  std::string known;
  for (const auto& m : cross_wlf_library()) {
    if (normalized(m.name) == normalized(name)) return m;
    known += (known.empty() ? "" : ", ") + m.name;
  }
  throw InputError("unknown material '" + std::string(name) + "' (known: " + known + ")");
}

std::string to_string(ViscosityModel m) {
  switch (m) {
    case ViscosityModel::newtonian: return "newtonian";
    case ViscosityModel::power_law: return "power-law";
    case ViscosityModel::cross: return "cross";
    case ViscosityModel::cross_wlf: return "cross-wlf";
    case ViscosityModel::carreau_yasuda: return "carreau-yasuda";
  }
  return "?";
}

std::string to_string(TemperatureShift s) {
  switch (s) {
    case TemperatureShift::none: return "none";
    case TemperatureShift::arrhenius: return "arrhenius";
    case TemperatureShift::wlf: return "wlf";
  }
  return "?";
}

ViscosityModel parse_viscosity_model(std::string_view name) {
  const auto s = normalized(name);
  for (auto m : {ViscosityModel::newtonian, ViscosityModel::power_law, ViscosityModel::cross, ViscosityModel::cross_wlf,
                 ViscosityModel::carreau_yasuda})
    if (s == to_string(m)) return m;
  throw InputError("unknown viscosity model '" + std::string(name) +
                   "' (known: newtonian, power-law, cross, cross-wlf, carreau-yasuda)");
}

TemperatureShift parse_temperature_shift(std::string_view name) {
  const auto s = normalized(name);
  for (auto t : {TemperatureShift::none, TemperatureShift::arrhenius, TemperatureShift::wlf})
    if (s == to_string(t)) return t;
  throw InputError("unknown temperature shift '" + std::string(name) + "' (known: none, arrhenius, wlf)");
}

std::vector<std::string> viscosity_param_names(ViscosityModel m) {
  switch (m) {
    case ViscosityModel::newtonian: return {"eta0_Pa_s"};
    case ViscosityModel::power_law: return {"K_Pa_s_n", "n"};
    case ViscosityModel::cross: return {"eta0_Pa_s", "tau_star_Pa", "n"};
    case ViscosityModel::cross_wlf: return {"n", "tau_star_Pa", "D1_Pa_s", "D2_K", "D3_K_per_Pa", "A1", "A2_K"};
    case ViscosityModel::carreau_yasuda: return {"eta0_Pa_s", "eta_inf_Pa_s", "lambda_s", "a", "n"};
  }
  return {};
}

std::vector<std::string> shift_param_names(TemperatureShift s) {
  switch (s) {
    case TemperatureShift::none: return {};
    case TemperatureShift::arrhenius: return {"Ea_J_per_mol"};
    case TemperatureShift::wlf: return {"C1", "C2_K"};
  }
  return {};
}

double ViscositySpec::viscosity(double g, double T, double p) const {
  const auto v = [this](const char* k) { return values.at(k); };
  double aT = 1.0;
  if (shift == TemperatureShift::arrhenius) aT = arrhenius_shift(T, v("Ea_J_per_mol"), v("T_ref_K"));
  else if (shift == TemperatureShift::wlf) aT = wlf_shift(T, v("C1"), v("C2_K"), v("T_ref_K"));
  switch (model) {
    case ViscosityModel::newtonian: return v("eta0_Pa_s") * aT;
    case ViscosityModel::power_law: return power_law_viscosity(v("K_Pa_s_n") * aT, v("n"), g);
    case ViscosityModel::cross: return cross_viscosity(v("eta0_Pa_s") * aT, v("tau_star_Pa"), v("n"), g);
    case ViscosityModel::cross_wlf:
      return cross_wlf_viscosity(
          {v("n"), v("tau_star_Pa"), v("D1_Pa_s"), v("D2_K"), v("D3_K_per_Pa"), v("A1"), v("A2_K")}, g, T, p);
    case ViscosityModel::carreau_yasuda:
      return carreau_yasuda_viscosity(v("eta0_Pa_s") * aT, v("eta_inf_Pa_s") * aT, v("lambda_s") * aT, v("a"), v("n"),
                                      g);
  }
  return 0;
}

double ViscositySpec::local_flow_index(double g, double T, double p) const {
  const double h = 1e-4;  // relative step in ln(gamma)
  const double up = std::log(viscosity(g * std::exp(h), T, p));
  const double dn = std::log(viscosity(g * std::exp(-h), T, p));
  return 1.0 + (up - dn) / (2 * h);
}

std::string ViscositySpec::name() const {
  std::string s = to_string(model);
  if (shift != TemperatureShift::none) s += "+" + to_string(shift);
  return s;
}

ViscositySpec ViscositySpec::from_cross_wlf(const CrossWlfParams& c) {
  ViscositySpec s;
  s.model = ViscosityModel::cross_wlf;
  s.values = {{"n", c.n},       {"tau_star_Pa", c.tau_star_Pa}, {"D1_Pa_s", c.D1_Pa_s},
              {"D2_K", c.D2_K}, {"D3_K_per_Pa", c.D3_K_per_Pa}, {"A1", c.A1},
              {"A2_K", c.A2_K}};
  return s;
}

ViscositySpec parse_viscosity_spec_name(std::string_view name) {
  ViscositySpec s;
  const auto plus = name.find('+');
  s.model = parse_viscosity_model(name.substr(0, plus));
  s.shift = plus == std::string_view::npos ? TemperatureShift::none : parse_temperature_shift(name.substr(plus + 1));
  return s;
}

}  // namespace tunekit::fitting
