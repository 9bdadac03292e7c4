#pragma once
// Small statistics used by every fit: Student-t quantiles for confidence intervals,
// the Ljung-Box whiteness test of residuals, and information criteria.

#include <span>
#include <vector>

namespace tunekit::fitting {

/// The two-sided 95 % quantile of the standard normal: a normal 95 % interval is value +- kZ95 stderr.
inline constexpr double kZ95 = 1.959963984540054;

/// Two-sided Student-t multiplier: the t value with `dof` degrees of freedom such that
/// P(|T| <= t) = confidence. Falls back to the normal quantile for dof <= 0 or huge dof.
double t_multiplier(double confidence, double dof);

/// P(F >= f) for Fisher's F distribution with (df1, df2) degrees of freedom: the p-value of an
/// F test that a model's extra parameters explain no variance.
double f_test_p_value(double f, double df1, double df2);

/// Ljung-Box portmanteau test of residual whiteness over `lags` lags.
struct WhitenessTest {
  double q = 0;        ///< test statistic
  double p_value = 1;  ///< P(chi2(lags) >= q); small means correlated residuals
  int lags = 0;
};
WhitenessTest ljung_box(std::span<const double> residuals, int lags);
/// The same test, without a buffer of the residuals' length: `residuals` is overwritten (with
/// their deviations from the mean in reverse order). The statistic is the same to the bit.
WhitenessTest ljung_box_in_place(std::span<double> residuals, int lags);

/// Variance factor of a fit whose residuals are correlated in time: 1 + 2 sum of the residuals'
/// autocorrelation up to its first non-positive lag (at most n / 10 lags, 2000), at least 1. The
/// parameters' variances from s^2 (J^T J)^-1 are multiplied by it (the effective number of
/// independent residuals is n / f: Bartlett, "Some aspects of the time-correlation problem in
/// regard to tests of significance", 1935). 1 for white residuals.
double residual_variance_factor(std::span<const double> residuals);

/// Median of `v` (taken by value: it is partially reordered). 0 for an empty vector.
double median(std::vector<double> v);
/// The same median without a copy: `v` is partially reordered in place.
double median_in_place(std::span<double> v);
/// The median of the intervals t[i] - t[i - 1] (as median() takes it), 0 for fewer than 2
/// instants. When they take at most 8 distinct values (a regular clock's intervals differ only by
/// the rounding of its instants) they are counted without a buffer; otherwise they are written to
/// `scratch` when it holds t.size() - 1 values (it is overwritten), or to a buffer of their own.
double median_interval(std::span<const double> t, std::span<double> scratch = {});

/// Default number of lags for Ljung-Box: min(20, n/4), at least 1.
int default_whiteness_lags(std::size_t n);

}  // namespace tunekit::fitting
