// The Ljung-Box test from sums a caller has already taken: for fill_residual_diagnostics_in_place,
// which takes the residuals' mean and squared deviations in the passes of its other statistics.
#pragma once

#include <span>

#include "tunekit/fitting/stats.hpp"

namespace tunekit::fitting::whiteness_detail {

/// ljung_box_in_place(r, lags) for residuals whose mean is `mean` and whose sum of squared
/// deviations from it is c0 (each summed in the order of the samples, as ljung_box sums them):
/// the same statistic to the bit; r is overwritten. n >= 3, lags >= 1.
WhitenessTest ljung_box_in_place(std::span<double> r, double mean, double c0, int lags);

}  // namespace tunekit::fitting::whiteness_detail
