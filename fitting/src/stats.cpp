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
  double q = 0;
  for (int k = 1; k <= lags; ++k) {
    double ck = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < n; ++i) ck += (r[i] - mean) * (r[i - k] - mean);
    const double rho = ck / c0;
    q += rho * rho / static_cast<double>(n - static_cast<std::size_t>(k));
  }
  q *= static_cast<double>(n) * (static_cast<double>(n) + 2.0);
  t.q = q;
  t.lags = lags;
  t.p_value = boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<>(lags), q));
  return t;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace tunekit::fitting
