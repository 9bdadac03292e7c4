#include "tunekit/fitting/stats.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace tunekit::fitting {

double t_multiplier(double confidence, double dof) {
  const double p = 0.5 + 0.5 * confidence;
  if (!(dof > 0) || dof > 1e7) return boost::math::quantile(boost::math::normal_distribution<>(), p);
  return boost::math::quantile(boost::math::students_t_distribution<>(dof), p);
}

int default_whiteness_lags(std::size_t n) { return static_cast<int>(std::clamp<std::size_t>(n / 4, 1, 20)); }

WhitenessTest ljung_box(std::span<const double> r, int lags) {
  WhitenessTest t;
  const std::size_t n = r.size();
  if (n < 3 || lags < 1) return t;
  lags = std::min<int>(lags, static_cast<int>(n) - 1);
  double mean = 0;
  for (double v : r) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  if (!(c0 > 0)) return t;
  // The autocovariances c_k = sum_{i >= k} (r_i - mean)(r_{i-k} - mean), four lags per pass over
  // the residuals: the four sums do not wait for each other's additions (one sum at a time is
  // bound by the latency of its additions). Each sum still adds its terms in the order of i, so
  // every c_k is rounded exactly as one lag at a time would round it.
  std::vector<double> c(static_cast<std::size_t>(lags) + 1, 0.0);
  constexpr int kBlock = 4;
  int k = 1;
  for (; k + kBlock - 1 <= lags; k += kBlock) {
    const auto k0 = static_cast<std::size_t>(k);
    double a[kBlock] = {0, 0, 0, 0};
    // Lag k + m starts at i = k + m (lags <= n - 1, so these i are samples).
    for (std::size_t i = k0; i < k0 + kBlock - 1; ++i)
      for (std::size_t m = 0; k0 + m <= i; ++m) a[m] += (r[i] - mean) * (r[i - k0 - m] - mean);
    for (std::size_t i = k0 + kBlock - 1; i < n; ++i) {
      const double di = r[i] - mean;
      for (std::size_t m = 0; m < kBlock; ++m) a[m] += di * (r[i - k0 - m] - mean);
    }
    for (std::size_t m = 0; m < kBlock; ++m) c[k0 + m] = a[m];
  }
  for (; k <= lags; ++k) {
    double ck = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < n; ++i) ck += (r[i] - mean) * (r[i - k] - mean);
    c[static_cast<std::size_t>(k)] = ck;
  }
  double q = 0;
  for (k = 1; k <= lags; ++k) {
    const double rho = c[static_cast<std::size_t>(k)] / c0;
    q += rho * rho / static_cast<double>(n - static_cast<std::size_t>(k));
  }
  q *= static_cast<double>(n) * (static_cast<double>(n) + 2.0);
  t.q = q;
  t.lags = lags;
  t.p_value = boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<>(lags), q));
  return t;
}

double residual_variance_factor(std::span<const double> r) {
  const std::size_t n = r.size();
  if (n < 2) return 1;
  double mean = 0;
  for (double v : r) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  if (!(c0 > 0)) return 1;
  double f = 1;
  const std::size_t max_lag = std::min<std::size_t>(n / 10, 2000);
  for (std::size_t k = 1; k <= max_lag; ++k) {
    double ck = 0;
    for (std::size_t i = k; i < n; ++i) ck += (r[i] - mean) * (r[i - k] - mean);
    const double rho = ck / c0;
    if (!(rho > 0)) break;
    f += 2 * rho;
  }
  return std::max(1.0, f);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace tunekit::fitting
