#pragma once
// Helpers shared by the viscosity fits (rheology_fit.cpp) and the time-temperature
// superposition (rheology_superposition.cpp): parameter specifications, data statistics,
// validation and the translation of fitted ln-values back to public values. Private to fitting.

#include <limits>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
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

}  // namespace tunekit::fitting::rheology_detail
