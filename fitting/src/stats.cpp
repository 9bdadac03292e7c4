#include "tunekit/fitting/stats.hpp"

#include "whiteness_detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace tunekit::fitting {

double t_multiplier(double confidence, double dof) {
  const double p = 0.5 + 0.5 * confidence;
  if (!(dof > 0) || dof > 1e7) return boost::math::quantile(boost::math::normal_distribution<>(), p);
  return boost::math::quantile(boost::math::students_t_distribution<>(dof), p);
}

double f_test_p_value(double f, double df1, double df2) {
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f_distribution<>(df1, df2), f));
}

int default_whiteness_lags(std::size_t n) { return static_cast<int>(std::clamp<std::size_t>(n / 4, 1, 20)); }

namespace {

// The deviations r_i - mean in reverse order: rev[j] = r[n - 1 - j] - mean. `rev` may be `r`
// itself (then r is overwritten).
void reversed_deviations(std::span<const double> r, double mean, std::span<double> rev) {
  const std::size_t n = r.size();
  for (std::size_t j = 0; j < n / 2; ++j) {
    const double a = r[j], b = r[n - 1 - j];
    rev[j] = b - mean;
    rev[n - 1 - j] = a - mean;
  }
  if (n % 2 == 1) rev[n / 2] = r[n / 2] - mean;
}

// The autocovariances c[k0 .. k0 + 2 Pairs - 1] (Pairs 1 or 4) of the deviations d_i (given
// reversed, as reversed_deviations makes them) in one pass: c_k = sum_{i >= k} d_i d_{i-k}. Two
// lags share a register: d_{i-k} and d_{i-k-1} lie side by side in the reversed order, and each
// lane adds its own lag's terms in the order of i, so every c_k is rounded exactly as one lag at
// a time would round it (one sum at a time is bound by the latency of its additions).
template <std::size_t Pairs>
void autocovariance_block(std::span<const double> rev, std::size_t k0, std::vector<double>& c) {
  static_assert(Pairs == 1 || Pairs == 4);
  constexpr std::size_t kLags = 2 * Pairs;
  using Lanes = double __attribute__((vector_size(16)));
  const std::size_t n = rev.size();
  auto d = [&](std::size_t i) { return rev[n - 1 - i]; };
  auto load = [](const double* x) {
    Lanes v;
    std::memcpy(&v, x, sizeof v);
    return v;
  };
  double head[kLags] = {};
  // Lag k0 + m starts at i = k0 + m (lags <= n - 1, so these i are samples).
  for (std::size_t i = k0; i < k0 + kLags - 1; ++i)
    for (std::size_t m = 0; k0 + m <= i; ++m) head[m] += d(i) * d(i - k0 - m);
  // Four named sums, not an array: an array's elements would be stored and loaded every sample.
  Lanes a0 = {head[0], head[1]}, a1 = {0, 0}, a2 = {0, 0}, a3 = {0, 0};
  if constexpr (Pairs == 4) a1 = Lanes{head[2], head[3]}, a2 = Lanes{head[4], head[5]}, a3 = Lanes{head[6], head[7]};
  for (std::size_t i = k0 + kLags - 1; i < n; ++i) {
    const double di = d(i);
    const double* lag = rev.data() + (n - 1 - i + k0);  // lag[m] = d_{i - k0 - m}
    a0 += di * load(lag);
    if constexpr (Pairs == 4) {
      a1 += di * load(lag + 2);
      a2 += di * load(lag + 4);
      a3 += di * load(lag + 6);
    }
  }
  const Lanes sums[4] = {a0, a1, a2, a3};
  for (std::size_t q = 0; q < Pairs; ++q) {
    c[k0 + 2 * q] = sums[q][0];
    c[k0 + 2 * q + 1] = sums[q][1];
  }
}

// The autocovariances c[k0 .. k0 + 19] in one pass, as autocovariance_block but with 20 lags in
// five registers of four lanes: the pass is bound by the latency of each register's additions, so
// twenty lags cost what eight did. Each lane still adds its own lag's terms in the order of i, so
// every c_k is the same to the bit. Compiled for AVX2 beside the baseline (one 4-lane register
// there, two 2-lane registers in the baseline); AVX2 alone does not contract into FMA, so both
// clones round alike.
[[gnu::target_clones("avx2", "default")]] void autocovariance_20(std::span<const double> rev, std::size_t k0,
                                                                 std::vector<double>& c) {
  constexpr std::size_t kLags = 20;
  using Lanes = double __attribute__((vector_size(32)));
  const std::size_t n = rev.size();
  auto d = [&](std::size_t i) { return rev[n - 1 - i]; };
  // By reference: a 4-lane vector returned by value would change the baseline clone's ABI.
  auto load = [](Lanes& v, const double* x) { std::memcpy(&v, x, sizeof v); };
  auto add = [](Lanes& a, double di, const double* x) {
    Lanes v;
    std::memcpy(&v, x, sizeof v);
    a += di * v;
  };
  double head[kLags] = {};
  for (std::size_t i = k0; i < k0 + kLags - 1; ++i)
    for (std::size_t m = 0; k0 + m <= i; ++m) head[m] += d(i) * d(i - k0 - m);
  Lanes a0, a1, a2, a3, a4;
  load(a0, head);
  load(a1, head + 4);
  load(a2, head + 8);
  load(a3, head + 12);
  load(a4, head + 16);
  for (std::size_t i = k0 + kLags - 1; i < n; ++i) {
    const double di = d(i);
    const double* lag = rev.data() + (n - 1 - i + k0);  // lag[m] = d_{i - k0 - m}
    add(a0, di, lag);
    add(a1, di, lag + 4);
    add(a2, di, lag + 8);
    add(a3, di, lag + 12);
    add(a4, di, lag + 16);
  }
  const Lanes sums[5] = {a0, a1, a2, a3, a4};
  for (std::size_t q = 0; q < 5; ++q)
    for (std::size_t l = 0; l < 4; ++l) c[k0 + 4 * q + l] = sums[q][l];
}

}  // namespace

namespace {

// The mean of r and the sum of squared deviations from it.
std::pair<double, double> mean_and_c0(std::span<const double> r) {
  double mean = 0;
  for (double v : r) mean += v;
  mean /= static_cast<double>(r.size());
  double c0 = 0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  return {mean, c0};
}

// Ljung-Box from the reversed deviations (reversed_deviations) and their c0.
WhitenessTest ljung_box_of_deviations(std::span<const double> rev, double c0, int lags) {
  WhitenessTest t;
  const std::size_t n = rev.size();
  // The autocovariances c_k = sum_{i >= k} (r_i - mean)(r_{i-k} - mean), several lags per pass
  // over the residuals (autocovariance_block).
  std::vector<double> c(static_cast<std::size_t>(lags) + 1, 0.0);
  int k = 1;
  for (; k + 19 <= lags; k += 20) autocovariance_20(rev, static_cast<std::size_t>(k), c);
  for (; k + 7 <= lags; k += 8) autocovariance_block<4>(rev, static_cast<std::size_t>(k), c);
  for (; k + 1 <= lags; k += 2) autocovariance_block<1>(rev, static_cast<std::size_t>(k), c);
  for (; k <= lags; ++k) {
    double ck = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < n; ++i) ck += rev[n - 1 - i] * rev[n - 1 - i + k];
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

}  // namespace

WhitenessTest ljung_box(std::span<const double> r, int lags) {
  const std::size_t n = r.size();
  if (n < 3 || lags < 1) return {};
  lags = std::min<int>(lags, static_cast<int>(n) - 1);
  const auto [mean, c0] = mean_and_c0(r);
  if (!(c0 > 0)) return {};
  std::vector<double> rev(n);
  reversed_deviations(r, mean, rev);
  return ljung_box_of_deviations(rev, c0, lags);
}

WhitenessTest ljung_box_in_place(std::span<double> r, int lags) {
  if (r.size() < 3 || lags < 1) return {};
  const auto [mean, c0] = mean_and_c0(r);
  return whiteness_detail::ljung_box_in_place(r, mean, c0, lags);
}

WhitenessTest whiteness_detail::ljung_box_in_place(std::span<double> r, double mean, double c0, int lags) {
  const std::size_t n = r.size();
  lags = std::min<int>(lags, static_cast<int>(n) - 1);
  if (!(c0 > 0)) return {};
  reversed_deviations(r, mean, r);
  return ljung_box_of_deviations(r, c0, lags);
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

namespace {

// The distinct values of a clock's intervals and how many intervals take each (at most 8).
struct IntervalCounts {
  static constexpr std::size_t kMax = 8;
  double values[kMax] = {};
  long count[kMax] = {};
  std::size_t distinct = 0;

  /// Counts the intervals t[i] - t[i - 1], i in [b, e), one at a time; false when a ninth value
  /// (or NaN) appears.
  bool add(const double* t, std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const double d = t[i] - t[i - 1];
      std::size_t j = 0;
      while (j < distinct && !(values[j] == d)) ++j;
      if (j == distinct) {
        if (distinct == kMax || std::isnan(d)) return false;
        values[distinct++] = d;
      }
      ++count[j];
    }
    return true;
  }

  /// The median (median()'s: the k-th smallest from 0, k = (number of intervals) / 2): the value
  /// with at most k intervals below it and more than k at or below it.
  double median(std::size_t intervals) const {
    const auto k = static_cast<long>(intervals / 2);
    for (std::size_t j = 0; j < distinct; ++j) {
      long at_or_below = 0;
      for (std::size_t m = 0; m < distinct; ++m)
        if (values[m] <= values[j]) at_or_below += count[m];
      if (at_or_below > k && at_or_below - count[j] <= k) return values[j];
    }
    return std::numeric_limits<double>::quiet_NaN();
  }
};

// median_interval when the intervals take at most 8 distinct values, without a buffer; NaN when
// they take more. A block of 256 intervals is counted four at a time against every value seen so
// far, without a branch; a block with a value not seen before is counted again one at a time,
// which adds it. Built for AVX2 beside the baseline.
[[gnu::target_clones("avx2", "default")]] double median_of_few_intervals(const double* t, std::size_t n) {
  using Lanes = double __attribute__((vector_size(32)));
  using Counts = decltype(Lanes{} == Lanes{});
  constexpr std::size_t kBlock = 256, kMax = IntervalCounts::kMax;
  IntervalCounts ic;
  Lanes a, b;
  for (std::size_t i = 1; i < n;) {
    const std::size_t e = std::min(n, i + kBlock), e4 = i + (e - i) / 4 * 4;
    Counts c[kMax] = {};
    if (ic.distinct > 0) {
      Lanes v[kMax];
      for (std::size_t j = 0; j < kMax; ++j)  // an empty slot is NaN: it equals nothing
        v[j] = Lanes{} + (j < ic.distinct ? ic.values[j] : std::numeric_limits<double>::quiet_NaN());
      for (std::size_t k = i; k < e4; k += 4) {
        std::memcpy(&a, t + k, sizeof a);
        std::memcpy(&b, t + k - 1, sizeof b);
        const Lanes d = a - b;
        for (std::size_t j = 0; j < kMax; ++j) c[j] -= (v[j] == d);  // a true lane is -1
      }
    }
    long block[kMax] = {}, counted = 0;
    for (std::size_t j = 0; j < kMax; ++j) counted += block[j] = c[j][0] + c[j][1] + c[j][2] + c[j][3];
    if (ic.distinct > 0 && counted == static_cast<long>(e4 - i)) {
      for (std::size_t j = 0; j < kMax; ++j) ic.count[j] += block[j];
      if (!ic.add(t, e4, e)) return std::numeric_limits<double>::quiet_NaN();
    } else if (!ic.add(t, i, e)) {
      return std::numeric_limits<double>::quiet_NaN();
    }
    i = e;
  }
  return ic.median(n - 1);
}

}  // namespace

double median_interval(std::span<const double> t, std::span<double> scratch) {
  const std::size_t n = t.size();
  if (n < 2) return 0;
  if (const double dt = median_of_few_intervals(t.data(), n); !std::isnan(dt)) return dt;
  std::vector<double> own;
  if (scratch.size() < n - 1) {
    own.resize(n - 1);
    scratch = own;
  }
  const std::span<double> d = scratch.first(n - 1);
  for (std::size_t i = 1; i < n; ++i) d[i - 1] = t[i] - t[i - 1];
  return median_in_place(d);
}

double median(std::vector<double> v) { return median_in_place(v); }

double median_in_place(std::span<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace tunekit::fitting
