#pragma once
// Helpers shared by the viscosity fits (rheology_fit.cpp) and the time-temperature
// superposition (rheology_superposition.cpp): parameter specifications, data statistics,
// validation and the translation of fitted ln-values back to public values. Private to fitting.

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/rheology_fit.hpp"

namespace tunekit::fitting::rheology_detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// printf-style message formatting (the fitting layer does not depend on fmt).
[[gnu::format(printf, 1, 2)]] std::string strf(const char* f, ...);

// One parameter as estimated: `log` ones are estimated as ln(value).
struct PSpec {
  std::string name;
  std::string unit;
  bool log = false;
  double lo = -kInf, hi = kInf, start = 0;
  bool fixed = false;
};

struct DataStats {
  double eta_min = kInf, eta_max = 0, eta_med = 0, g_med = 0;
  std::vector<double> levels;
};

/// Extremes and medians of the data and its temperature levels.
DataStats stats_of(const RheologyData& d);
/// The reference temperature when none is given: the middle level.
double default_T_ref(const std::vector<double>& levels);
/// InputError for empty, mismatched or non-positive data.
void validate_data(const RheologyData& d);
/// Replaces the core's bound warnings (which show ln values) by ones with public values.
void finish_params(FitResult& fit, const std::vector<PSpec>& specs);
/// Number of parameters that are not fixed.
int free_count(const std::vector<PSpec>& specs);

/// ln of the Cross viscosity eta0 / (1 + (eta0 g / tau*)^(1-n)) from ln eta0, ln g (1/s),
/// ln tau* (Pa) and n; when d is not null, d[0..2] are its derivatives in ln eta0, ln tau* and n.
/// NaN where the power overflows.
double ln_cross_viscosity(double ln_eta0, double ln_g, double ln_tau_star, double n, double* d);

/// ln viscosity of a model with its temperature shift at one point, from the parameters as the
/// fits estimate them (default_specs' order; ln of the `log` ones), and its gradient in them.
class LnViscosity {
 public:
  LnViscosity(ViscosityModel model, TemperatureShift shift);
  /// Parameters: the model's, the shift's and T_ref_K (with a shift).
  std::size_t size() const { return size_; }
  /// ln eta at ln g (1/s), T (K) and pressure (Pa); when d is not null, d[0..size) its gradient.
  /// False outside the model's domain.
  bool operator()(const double* p, double ln_g, double T, double pressure, double& ln_eta, double* d) const;

 private:
  ViscosityModel model_;
  TemperatureShift shift_;
  std::size_t offset_ = 0, size_ = 0;  // where the shift's parameters start; all parameters
};

/// What the viscosity residuals read per point: ln shear rate, ln viscosity, sqrt(weight),
/// temperature (K) and pressure (Pa, 0 without a column).
struct ViscosityRows {
  std::vector<double> ln_g, ln_obs, sw, T, pressure;
};
ViscosityRows viscosity_rows(const RheologyData& data);

/// `base` with the residuals sw (ln eta - ln eta_observed) of the points idx and their analytic
/// Jacobian; `rows` must outlive the problem.
LsqProblem viscosity_problem(LsqProblem base, const ViscosityRows& rows, std::vector<std::size_t> idx,
                             const LnViscosity& ln_eta);

/// A viscosity fit's least-squares problem: the parameters as estimated, the residuals of every
/// point and of the global search's evenly strided subset. Its residuals read `rows`, so it stays
/// where it was made (neither copied nor moved).
struct ViscosityProblem {
  ViscosityProblem() = default;
  ViscosityProblem(const ViscosityProblem&) = delete;
  ViscosityProblem& operator=(const ViscosityProblem&) = delete;
  std::string name;  ///< ViscositySpec::name()
  std::vector<PSpec> specs;
  DataStats stats;
  ViscosityRows rows;
  LsqProblem all, search;
};
/// Checks the data and the options against the model and sets up its problem (the InputErrors of
/// fit_viscosity).
std::unique_ptr<ViscosityProblem> viscosity_problem_for(const RheologyData& data, const ViscosityFitOptions& o);
/// The estimate in solver coordinates (ln of the `log` parameters): global search, then Ceres.
FitResult solve_viscosity(const ViscosityProblem& vp, const ViscosityFitOptions& o);
/// The rest of fit_viscosity on that estimate: profile intervals (o.profile_intervals), derived
/// viscosities, the Cross-WLF ridge warning and the public values.
FitResult finish_viscosity_fit(const RheologyData& data, const ViscosityFitOptions& o, const ViscosityProblem& vp,
                               FitResult estimate);

}  // namespace tunekit::fitting::rheology_detail
