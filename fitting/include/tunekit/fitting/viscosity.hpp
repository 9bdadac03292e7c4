#pragma once
// Melt viscosity models and temperature shifts (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente,
// 2019, sec. 2.2.2 and appendix A).
//
//   Newtonian        eta = eta0
//   power law        eta = K gamma^(n-1)
//   Cross (Moldflow) eta = eta0 / (1 + (eta0 gamma / tau*)^(1-n))
//   Cross-WLF        Cross with eta0 = D1 exp(-A1 (T - T*) / (A2 + T - T*)), T* = D2 + D3 p,
//                    and A2 = A3~ + D3 p (the A2_K parameter here is the value at the data's pressure)
//   Carreau-Yasuda   eta = eta_inf + (eta0 - eta_inf) (1 + (lambda gamma)^a)^((n-1)/a)
//
// Temperature shifts a_T(T) (time-temperature superposition) for every model but Cross-WLF:
//   Arrhenius  a_T = exp((Ea/R) (1/T - 1/T_ref))
//   WLF        a_T = exp(-C1 (T - T_ref) / (C2 + T - T_ref))
// The shift multiplies eta0 (Newtonian, Cross), K (power law, as in Holtrup 2019 sec. 5.2.3) and
// eta0, eta_inf and lambda (Carreau-Yasuda). Temperatures are kelvin everywhere in here.
//
// Temperature convention: Holtrup's (2019) code converts degC with +273, SI is +273.15. Both are
// explicit: celsius_to_kelvin(c, kKelvinOffsetThesis) reproduces the thesis' 346.4 Pa.s.

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace tunekit::fitting {

inline constexpr double kKelvinOffset = 273.15;       ///< SI: T[K] = T[degC] + 273.15
inline constexpr double kKelvinOffsetThesis = 273.0;  ///< Holtrup 2019 appendix A code: + 273
inline constexpr double kGasConstant = 8.314462618;   ///< J/(mol K)

inline double celsius_to_kelvin(double degc, double offset = kKelvinOffset) { return degc + offset; }

/// The seven Cross-WLF coefficients, named as in the JSON output.
struct CrossWlfParams {
  double n = 0;
  double tau_star_Pa = 0;
  double D1_Pa_s = 0;
  double D2_K = 0;
  double D3_K_per_Pa = 0;
  double A1 = 0;
  double A2_K = 0;  ///< A3~ (Table 2.4's "A3") at zero pressure
};

/// Zero-shear viscosity eta0(T, p) of the Cross-WLF model (Pa.s).
double cross_wlf_zero_shear(const CrossWlfParams& c, double temperature_K, double pressure_Pa = 0);
/// Cross-WLF viscosity (Pa.s) at a shear rate (1/s), temperature (K) and pressure (Pa).
double cross_wlf_viscosity(const CrossWlfParams& c, double shear_rate_1_s, double temperature_K,
                           double pressure_Pa = 0);

double cross_viscosity(double eta0_Pa_s, double tau_star_Pa, double n, double shear_rate_1_s);
double power_law_viscosity(double K_Pa_s_n, double n, double shear_rate_1_s);
double carreau_yasuda_viscosity(double eta0_Pa_s, double eta_inf_Pa_s, double lambda_s, double a, double n,
                                double shear_rate_1_s);
double arrhenius_shift(double temperature_K, double Ea_J_per_mol, double T_ref_K);
double wlf_shift(double temperature_K, double C1, double C2_K, double T_ref_K);

/// A material of Holtrup 2019 Table 2.4 / appendix A (Solidworks 2018 data).
struct CrossWlfMaterial {
  std::string name;
  CrossWlfParams params;
  double T_min_K = 0;  ///< validity range; 0 when Holtrup (2019) gives none
  double T_max_K = 0;
};
/// PEEK, ABS and ULTEM1010 as printed in Holtrup (2019).
const std::vector<CrossWlfMaterial>& cross_wlf_library();
/// Case-insensitive lookup ("peek", "ULTEM1010"); InputError listing the known names.
const CrossWlfMaterial& cross_wlf_material(std::string_view name);

enum class ViscosityModel { newtonian, power_law, cross, cross_wlf, carreau_yasuda };
enum class TemperatureShift { none, arrhenius, wlf };

std::string to_string(ViscosityModel m);    ///< "newtonian", "power-law", "cross", "cross-wlf", "carreau-yasuda"
std::string to_string(TemperatureShift s);  ///< "none", "arrhenius", "wlf"
/// Accepts the names above (and '_' for '-'); InputError otherwise.
ViscosityModel parse_viscosity_model(std::string_view name);
TemperatureShift parse_temperature_shift(std::string_view name);

/// Names (in the order used by the fits) of a model's own parameters, without shift parameters.
std::vector<std::string> viscosity_param_names(ViscosityModel m);
/// Names of a shift's parameters ("Ea_J_per_mol", or "C1", "C2_K"; T_ref_K is stored as well).
std::vector<std::string> shift_param_names(TemperatureShift s);

/// A fully specified viscosity function: model, shift and parameter values by name
/// (including "T_ref_K" when shifted). Built from a fit or from the material library.
struct ViscositySpec {
  ViscosityModel model = ViscosityModel::cross_wlf;
  TemperatureShift shift = TemperatureShift::none;
  std::map<std::string, double> values;

  /// Throws std::out_of_range when a needed parameter is missing.
  double viscosity(double shear_rate_1_s, double temperature_K, double pressure_Pa = 0) const;
  /// d ln(eta) / d ln(gamma) + 1: the local power-law index at this shear rate.
  double local_flow_index(double shear_rate_1_s, double temperature_K, double pressure_Pa = 0) const;
  /// "cross-wlf", "cross+arrhenius", ... (the FitResult model name)
  std::string name() const;

  static ViscositySpec from_cross_wlf(const CrossWlfParams& c);
};

/// Parses a FitResult model name as written by ViscositySpec::name().
ViscositySpec parse_viscosity_spec_name(std::string_view name);

}  // namespace tunekit::fitting
