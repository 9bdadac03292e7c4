#pragma once
// Pressure drop of a melt through a printer nozzle (Holtrup 2019 sec. 2.2.1, 5.2.3, appendices F, J).
// SI units throughout: flow in m^3/s, lengths in m, angles in rad, pressures in Pa.
//
//   Hagen-Poiseuille (Newtonian)   dP = 128 mu l Q / (pi d^4)                               (eq. 2.1)
//   power-law capillary            dP = (4 l / d) K gw^n, gw = ((3n+1)/(4n)) 32 Q / (pi d^3)
//                                  (wall shear rate with the Rabinowitsch correction, eq. 2.14)
//   Bellini three-zone             melt room + cone + capillary, m = 1/n, phi = K^(-1/n),
//                                  v = 4 Q / (pi D^2) the filament speed (eq. 2.2-2.5)
//   Boles                          dP = K gw^n [1.18 / n^0.7 + 4 l / d + f(alpha)]          (eq. 2.6-2.7)
//                                  f(alpha) = 2/(3 n sin a) [3 sin a / (4 n (1-cos a)^2 (1+2 cos a))]^n
//
// Notes on the thesis text as extracted: eq. 2.4 as extracted lacks the (v/phi)^(1/m) factor and eq. 2.5 the
// square on D1/2; both are restored here (dimensionally required, and both reduce to
// Hagen-Poiseuille for n = 1; the tests check that).
//
// For a viscosity model that is not a power law (Cross, Cross-WLF, Carreau-Yasuda) the
// pressure-drop models use the local power law (K, n) at the nozzle's wall shear rate.

#include <string>
#include <string_view>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/viscosity.hpp"

namespace tunekit::fitting {

struct NozzleGeometry {
  double d_m = 0.6e-3;                              ///< nozzle channel (land) diameter
  double l_m = 4e-3;                                ///< land length
  double cone_half_angle_rad = 0.5235987755982988;  ///< alpha (Boles); Bellini's beta = 2 alpha
  double D_m = 5e-3;                                ///< melt room / entrance diameter
  double melt_length_m = 10e-3;                     ///< Bellini's L1 (the seed: any 1..30 mm changes dP < 5 %)
};

/// Throws InputError for non-positive or inconsistent dimensions (d >= D, alpha outside (0, 90 deg)).
void validate(const NozzleGeometry& g);

enum class PressureModel { hagen_poiseuille, power_law_capillary, bellini, boles };
std::string to_string(PressureModel m);  ///< "hagen-poiseuille", "power-law", "bellini", "boles"
PressureModel parse_pressure_model(std::string_view name);

/// Wall shear rate (1/s) with the Rabinowitsch correction for a power-law index n.
double wall_shear_rate(double n, double flow_m3_s, double d_m);
/// Apparent (Newtonian) wall shear rate 32 Q / (pi d^3) (1/s).
double apparent_wall_shear_rate(double flow_m3_s, double d_m);

double hagen_poiseuille_dp(double viscosity_Pa_s, double flow_m3_s, const NozzleGeometry& g);
double power_law_capillary_dp(double K_Pa_s_n, double n, double flow_m3_s, const NozzleGeometry& g);
double bellini_dp(double K_Pa_s_n, double n, double flow_m3_s, const NozzleGeometry& g);
double boles_dp(double K_Pa_s_n, double n, double flow_m3_s, const NozzleGeometry& g);
/// Boles' cone term f(alpha) (eq. 2.7) and entrance term 1.18 / n^0.7.
double boles_cone_term(double n, double alpha_rad);
double boles_entrance_term(double n);

/// Pressure drop (Pa) for a power-law fluid; Hagen-Poiseuille uses mu = K and ignores n.
double pressure_drop(PressureModel m, double K_Pa_s_n, double n, double flow_m3_s, const NozzleGeometry& g);
/// d(dP)/dQ (Pa s / m^3) for a power-law fluid: n dP / Q (dP / Q for Hagen-Poiseuille).
double pressure_drop_slope(PressureModel m, double K_Pa_s_n, double n, double flow_m3_s, const NozzleGeometry& g);

/// The power law that matches a viscosity model at the nozzle's wall shear rate.
struct LocalPowerLaw {
  double K_Pa_s_n = 0;
  double n = 1;
  double wall_shear_rate_1_s = 0;
};
LocalPowerLaw local_power_law(const ViscositySpec& v, double flow_m3_s, double d_m, double temperature_K,
                              double pressure_Pa = 0);

/// Pressure drop (Pa) with a general viscosity model (its local power law at the wall).
double pressure_drop(PressureModel m, const ViscositySpec& v, double flow_m3_s, double temperature_K,
                     const NozzleGeometry& g);
/// Incremental flow resistance d(dP)/dQ (Pa s / m^3) at an operating flow (central difference).
double pressure_drop_slope(PressureModel m, const ViscositySpec& v, double flow_m3_s, double temperature_K,
                           const NozzleGeometry& g);

/// Holtrup 2019 eq. 5.10/5.11 as coded in sec. 5.2.3 (PEEK 450G power law fitted to Cross-WLF over
/// 600..950 1/s): K = 10^20.14448 T^-6.22882 Pa.s^n, n = 0.17651 + 8.956e-4 T, T in degC.
struct PowerLawCoefficients {
  double K_Pa_s_n = 0;
  double n = 0;
};
PowerLawCoefficients holtrup_peek_power_law(double temperature_degC);

/// Steady nozzle measurements (Holtrup 2019 sec. 5.3: load cell force -> pressure, flow from the
/// feed rate, melt temperature from a thermal camera).
struct NozzleFlowData {
  std::vector<double> flow_m3_s;
  std::vector<double> pressure_Pa;
  std::vector<double> temperature_K;  ///< one per point
};

/// Inverse fit of the power law K (Pa.s^n) and n from measured pressure drops with the given
/// pressure-drop model and geometry: least squares on ln(dP), global start, Ceres refinement.
/// With data at several temperatures K carries an Arrhenius shift (Ea_J_per_mol, T_ref_K).
/// Hagen-Poiseuille fits a Newtonian viscosity mu_Pa_s instead. InputError for non-positive
/// data or too few points; FitError when the fit fails.
FitResult fit_nozzle_rheology(const NozzleFlowData& data, PressureModel model, const NozzleGeometry& g,
                              double T_ref_K = kNaN);

}  // namespace tunekit::fitting
