#pragma once
// Fitting melt viscosity models to rheometer data (Holtrup 2019 sec. 2.2.2, 5.2.3):
//  - weighted least squares on ln(eta) with bounds (Ceres) and an analytic Jacobian, start
//    values from a bounded global search (global_start.hpp), so no fit needs a guess from the user;
//  - 95 % intervals: scale parameters (eta0, K, tau*, D1, lambda) are estimated as logarithms,
//    so their intervals are exp of an interval in ln and never go negative; the reported std.
//    error is the delta-method value * se(ln). Where the linearised interval cannot be trusted
//    (Cross-WLF's D1, D2, A1 on the WLF ridge of data at few temperatures, a curved likelihood,
//    a bound nearby) it is replaced by the profile-likelihood interval (profile_likelihood.hpp);
//    an interval never leaves the parameter's search box (it ends there, with a warning);
//  - the zero-shear viscosity at each measured temperature as a derived quantity with its own
//    interval (FitResult::derived), and the correlation matrix (FitResult::covariance);
//  - information criteria finite for exact fits (least_squares.hpp: a residual-variance floor);
//  - AIC-based comparison of several models on the same data;
//  - a power-law fit to a model over a shear-rate window with log-spaced points (sec. 5.2.3:
//    evenly spaced points would weight the window's upper end);
//  - time-temperature superposition: shift factors per temperature and a master curve.
// Everything is SI (1/s, Pa.s, K, Pa); conversion from files happens in ident/rheology_data.

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/global_start.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/profile_likelihood.hpp"
#include "tunekit/fitting/viscosity.hpp"

namespace tunekit::fitting {

struct RheologyData {
  std::vector<double> shear_rate_1_s;
  std::vector<double> viscosity_Pa_s;
  std::vector<double> temperature_K;  ///< one per point
  std::vector<double> pressure_Pa;    ///< empty, or one per point
  std::vector<double> weight;         ///< empty (all 1), or one per point, > 0
  std::size_t size() const { return shear_rate_1_s.size(); }
  /// Distinct temperature levels (points within 0.05 K are one level), ascending.
  std::vector<double> temperature_levels_K() const;
};

struct ViscosityFitOptions {
  ViscosityModel model = ViscosityModel::cross_wlf;
  /// Temperature shift for the models other than Cross-WLF. With data at one temperature
  /// it must be none; with several, a model without a shift is an InputError.
  TemperatureShift shift = TemperatureShift::none;
  double T_ref_K = kNaN;  ///< shift reference; NaN: the temperature level nearest the median
  /// Parameters held at a value (e.g. {"D2_K", 416}). By default Cross-WLF holds A2_K = 51.6 K
  /// and D3_K_per_Pa = 0 (no pressure data), Carreau-Yasuda eta_inf_Pa_s = 0.
  std::map<std::string, double> fixed;
  /// Default-held parameters to estimate instead (e.g. "A2_K").
  std::vector<std::string> free;
  GlobalStartOptions global;
  LsqOptions lsq;
  /// Replace linearised intervals that cannot be trusted (correlation, curvature, a bound) by
  /// profile-likelihood intervals (profile_likelihood.hpp); Param::ci95_method says which.
  bool profile_intervals = true;
  ProfileOptions profile;
};

/// Fits the model. InputError: bad data (non-positive values, too few points for the free
/// parameters, one temperature for a temperature-dependent model); FitError: no convergence
/// or not identifiable. The FitResult's model is ViscositySpec::name(); it also lists
/// fixed parameters (T_ref_K, A2_K, ...) with fixed = true.
FitResult fit_viscosity(const RheologyData& data, const ViscosityFitOptions& options);

/// The viscosity function of a fit (the values of every parameter, fixed or not).
ViscositySpec spec_from_fit(const FitResult& fit);

struct ModelComparisonEntry {
  std::string model;
  bool ok = false;
  std::string error;  ///< why the model could not be fitted
  int num_parameters = 0;
  double aic = kNaN, bic = kNaN, delta_aic = kNaN, akaike_weight = kNaN, rms_ln = kNaN;
};
struct ModelComparison {
  std::vector<ModelComparisonEntry> entries;
  std::vector<FitResult> fits;  ///< parallel to entries (default FitResult where !ok)
  std::string best;             ///< lowest AIC
};
/// Fits every candidate to the same data and ranks them by AIC (Akaike weights). AICs within
/// 1e-9 relative tie (equivalent models), and a tie goes to the earlier candidate. The winner's
/// fit, and candidate `also_finish`'s when it is one (the model a user asked for), carry their
/// intervals as fit_viscosity gives them (profile likelihood where needed); the others' are the
/// linearised ones.
ModelComparison compare_viscosity_models(const RheologyData& data, const std::vector<ViscosityFitOptions>& candidates,
                                         std::size_t also_finish = static_cast<std::size_t>(-1));
/// The default candidates for these data (with shifts when there are several temperatures).
std::vector<ViscosityFitOptions> default_candidates(const RheologyData& data, const ViscosityFitOptions& base = {});
nlohmann::json to_json(const ModelComparison& c);

/// Power law K gamma^(n-1) fitted to a viscosity model over [lo, hi] 1/s with `points`
/// log-spaced shear rates (linear regression of log10 tau on log10 gamma). Params
/// K_Pa_s_n and n. Holtrup's (2019) procedure (sec. 5.2.3): 600..950 1/s, 50 points.
FitResult fit_power_law_window(const ViscositySpec& v, double temperature_K, double lo_1_s, double hi_1_s,
                               int points = 50, double pressure_Pa = 0);

struct TtsResult {
  double T_ref_K = kNaN;
  std::vector<double> temperatures_K;
  std::vector<double> shift_factor;     ///< a_T per temperature (1 at T_ref)
  std::vector<double> shift_factor_lo;  ///< 95 % interval
  std::vector<double> shift_factor_hi;
  FitResult reference_fit;  ///< Cross at T_ref with ln a_T per other temperature
  FitResult arrhenius;      ///< Ea_J_per_mol fitted to ln a_T (needs >= 2 other temperatures)
  bool has_arrhenius = false;
  std::vector<double> reduced_shear_rate_1_s;  ///< a_T gamma
  std::vector<double> reduced_viscosity_Pa_s;  ///< eta / a_T
};
/// Shift factors and master curve from data at >= 2 temperatures (Cross at the reference).
TtsResult time_temperature_superposition(const RheologyData& data, double T_ref_K = kNaN);
nlohmann::json to_json(const TtsResult& t);

/// Does each temperature lie on one master curve? (Dealy and Plazek, Time-temperature
/// superposition -- a users guide, Rheology Bulletin 78, 2009: a transition, a degrading
/// sample or a change of mechanism shows as curves that do not superpose.)
///  - per temperature: the shift factor a_T with its interval (time_temperature_superposition),
///    and an F test of the temperature's own Cross fit (3 parameters) against the master curve
///    (1 shift): F = ((rss_master - rss_own) / 2) / s^2, s^2 pooled from every temperature's own
///    fit; p < alpha and an rms misfit on the master curve above kSuperpositionTolerance (in
///    ln viscosity): the temperature is off the master curve;
///  - between neighbouring temperatures: a_T must fall as T rises (the melt thins when heated);
///    a rise whose intervals do not overlap is a reversal -- a phase transition between the two
///    (e.g. liquid-crystalline to isotropic), which no single temperature shift can hold; the
///    F test is then repeated on each side of the reversals with that side's own master curve.
/// Misfit on the master curve (rms of ln viscosity) below which a temperature is not flagged
/// however significant: about 5 %, the repeatability of rotational and capillary rheometry.
inline constexpr double kSuperpositionTolerance = 0.05;
struct SuperpositionLevel {
  double temperature_K = kNaN;
  int points = 0;
  double shift_factor = kNaN, shift_lo = kNaN, shift_hi = kNaN;  ///< a_T and its 95 % interval
  double rms_master_ln = kNaN;                                   ///< rms of ln(viscosity) residuals on the master curve
  double rms_own_ln = kNaN;  ///< rms of the temperature's own Cross fit (NaN: < 5 points)
  double f_statistic = kNaN;
  double p_value = kNaN;  ///< NaN when not tested (too few points)
  bool on_master_curve = true;
  /// Side of the reversals (0 below the first): with a transition each side is tested against
  /// its own master curve (rms_master_ln, the statistic and the verdict are the side's).
  int segment = 0;
};
struct SuperpositionReversal {
  double lower_K = kNaN, upper_K = kNaN;  ///< neighbouring temperatures
  double ratio = kNaN;                    ///< a_T(upper) / a_T(lower), > 1
};
struct SuperpositionCheck {
  double alpha = 0.01;
  TtsResult tts;
  std::vector<SuperpositionLevel> levels;
  std::vector<SuperpositionReversal> reversals;
  bool superposes() const;  ///< every level on the master curve and no reversal
};
/// Needs data at >= 2 temperatures (InputError otherwise); FitError when the master curve cannot
/// be fitted at all.
SuperpositionCheck check_superposition(const RheologyData& data, double T_ref_K = kNaN, double alpha = 0.01);
nlohmann::json to_json(const SuperpositionCheck& c);

}  // namespace tunekit::fitting
