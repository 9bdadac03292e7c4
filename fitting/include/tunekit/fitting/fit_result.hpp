#pragma once
// The result every estimator in tunekit returns: named parameters with units, standard
// errors and 95 % intervals, and diagnostics of the fit. Serialized to the JSON shape
// `{model, params: {name: {value, stderr, ci95: [lo, hi], unit}}, diagnostics}`.

#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace tunekit::fitting {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// One fitted parameter. `std_error` and the interval are NaN when not computed.
struct Param {
  std::string name;
  double value = kNaN;
  double std_error = kNaN;
  double ci95_lo = kNaN;
  double ci95_hi = kNaN;
  std::string unit;    ///< SI unit, e.g. "s", "Pa.s^n", "1" for dimensionless
  bool fixed = false;  ///< held at its start value, not estimated
  /// How the interval was computed: "wald" (linearised, Student-t), "profile-likelihood"
  /// (profile_likelihood.hpp), or empty when not stated. Serialized as "ci95_method".
  std::string ci95_method = {};
};

/// Quality of a fit. `whiteness_p` is the Ljung-Box p-value of the residuals
/// (small values: the residuals are correlated, the model misses dynamics).
struct Diagnostics {
  bool converged = false;
  int num_observations = 0;
  int num_parameters = 0;  ///< estimated (free) parameters
  int iterations = 0;
  double rss = kNaN;  ///< residual sum of squares
  double rms = kNaN;  ///< sqrt(rss / n)
  double r2 = kNaN;   ///< 1 - rss / total sum of squares (NaN without observations)
  double aic = kNaN;  ///< n ln(rss/n) + 2k
  double bic = kNaN;  ///< n ln(rss/n) + k ln n
  double whiteness_p = kNaN;
  int whiteness_lags = 0;
  std::string solver;  ///< one-line solver report
};

struct FitResult {
  std::string model;
  std::vector<Param> params;
  Diagnostics diagnostics;
  std::vector<std::string> warnings;
  /// Covariance of the estimate, row-major params.size() x params.size(), in the coordinates
  /// the solver used (ln for parameters estimated as logarithms), scaled by the residual
  /// variance; rows and columns of fixed parameters are 0. Empty when not computed. Not part
  /// of to_json(FitResult); see correlation_json().
  std::vector<double> covariance = {};
  /// Quantities computed from the parameters with their own intervals (e.g. the zero-shear
  /// viscosity at each measured temperature), serialized under "derived".
  std::vector<Param> derived = {};

  const Param& param(const std::string& name) const;  ///< throws std::out_of_range
  double value(const std::string& name) const { return param(name).value; }
};

nlohmann::json to_json(const Param& p);
nlohmann::json to_json(const Diagnostics& d);
nlohmann::json to_json(const FitResult& r);
/// {"parameters": [free names], "matrix": [[r_ij]]} from FitResult::covariance (null if empty).
nlohmann::json correlation_json(const FitResult& r);

}  // namespace tunekit::fitting
