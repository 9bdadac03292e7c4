// The least-squares core: intervals, diagnostics, identifiability and convergence errors.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/interpolate.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/stats.hpp"

using namespace tunekit::fitting;

TEST_CASE("a straight line fit gives the textbook standard errors") {
  // y = a + b x; closed-form OLS standard errors to compare with.
  std::vector<double> x, y;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 0.1);
  for (int i = 0; i < 50; ++i) {
    x.push_back(i * 0.2);
    y.push_back(1.0 + 2.0 * x.back() + noise(rng));
  }
  LsqProblem p;
  p.params = {{"a", "1", 0}, {"b", "1", 0}};
  p.num_residuals = 50;
  p.observed = y;
  p.residuals = [&](const double* q, double* r) {
    for (int i = 0; i < 50; ++i) r[i] = q[0] + q[1] * x[i] - y[i];
    return true;
  };
  const auto fit = solve_least_squares("line", p);
  double sx = 0, sxx = 0;
  for (double v : x) sx += v, sxx += v * v;
  const double n = 50, sxx_c = sxx - sx * sx / n;
  const double s2 = fit.diagnostics.rss / (n - 2);
  CHECK(fit.param("b").std_error == Approx(std::sqrt(s2 / sxx_c)).epsilon(1e-6));
  CHECK(fit.param("a").std_error == Approx(std::sqrt(s2 * (1 / n + sx * sx / n / n / sxx_c))).epsilon(1e-6));
  // The whole covariance, off the diagonal too, symmetric: cov(a, b) = -s^2 mean(x) / Sxx.
  REQUIRE(fit.covariance.size() == 4);
  CHECK(fit.covariance[1] == Approx(-s2 * (sx / n) / sxx_c).epsilon(1e-6));
  CHECK(fit.covariance[2] == fit.covariance[1]);
  CHECK(fit.diagnostics.converged);
  CHECK(fit.diagnostics.r2 > 0.99);
  CHECK(fit.param("b").ci95_lo < 2.0);
  CHECK(fit.param("b").ci95_hi > 2.0);
  CHECK(fit.diagnostics.whiteness_p > 0.01);
}

TEST_CASE("a parameter the data cannot see is reported as not identifiable") {
  // y = a * exp(b x) * c: a and c are not separately identifiable.
  std::vector<double> x{0, 1, 2, 3, 4, 5}, y;
  for (double v : x) y.push_back(2 * std::exp(-0.5 * v));
  LsqProblem p;
  p.params = {{"a", "1", 1}, {"b", "1", -0.1}, {"c", "1", 1}};
  p.num_residuals = 6;
  p.residuals = [&](const double* q, double* r) {
    for (int i = 0; i < 6; ++i) r[i] = q[0] * q[2] * std::exp(q[1] * x[i]) - y[i];
    return true;
  };
  CHECK_THROWS_AS(solve_least_squares("degenerate", p), tunekit::FitError);
}

TEST_CASE("fewer data points than parameters is bad input") {
  LsqProblem p;
  p.params = {{"a", "1", 1}, {"b", "1", 1}};
  p.num_residuals = 1;
  p.residuals = [](const double* q, double* r) {
    r[0] = q[0] + q[1];
    return true;
  };
  CHECK_THROWS_AS(solve_least_squares("tiny", p), tunekit::InputError);
}

TEST_CASE("hitting the iteration limit is a fit failure, not a number") {
  std::vector<double> x{1, 2, 3, 4, 5, 6, 7, 8};
  LsqProblem p;
  p.params = {{"a", "1", 100}, {"b", "1", -3}};
  p.num_residuals = 8;
  p.residuals = [&](const double* q, double* r) {
    for (int i = 0; i < 8; ++i) r[i] = q[0] * std::exp(-q[1] * x[i]) - 5 * std::exp(-0.3 * x[i]);
    return true;
  };
  LsqOptions o;
  o.max_iterations = 1;
  CHECK_THROWS_AS(solve_least_squares("slow", p, o), tunekit::FitError);
}

TEST_CASE("Student-t multipliers and the Ljung-Box test") {
  CHECK(t_multiplier(0.95, 10) == Approx(2.228139).epsilon(1e-6));
  CHECK(t_multiplier(0.95, 1e9) == Approx(1.959964).epsilon(1e-6));
  std::vector<double> alternating;
  for (int i = 0; i < 100; ++i) alternating.push_back(i % 2 ? 1.0 : -1.0);
  CHECK(ljung_box(alternating, 10).p_value < 1e-6);
}

TEST_CASE("the Ljung-Box statistic over many lags is the definition's, to the bit") {
  // Its autocovariances are summed several lags to a register (on AVX2 where the processor has
  // it); each lag's terms are still added in sample order, as the definition below adds them.
  std::mt19937 rng(5);
  std::normal_distribution<double> e(0, 1);
  std::vector<double> r;
  double x = 0;
  for (int i = 0; i < 1000; ++i) r.push_back(x = 0.3 * x + e(rng));
  const int lags = 23;
  const double n = static_cast<double>(r.size());
  double mean = 0;
  for (double v : r) mean += v;
  mean /= n;
  double c0 = 0;
  for (double v : r) c0 += (v - mean) * (v - mean);
  double q = 0;
  for (int k = 1; k <= lags; ++k) {
    double ck = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < r.size(); ++i)
      ck += (r[i] - mean) * (r[i - static_cast<std::size_t>(k)] - mean);
    const double rho = ck / c0;
    q += rho * rho / (n - k);
  }
  q *= n * (n + 2.0);
  CHECK(ljung_box(r, lags).q == q);
  CHECK(ljung_box(r, lags).lags == lags);
}

TEST_CASE("the Ljung-Box test and the residual diagnostics in place are the same to the bit") {
  std::mt19937 rng(7);
  std::normal_distribution<double> e(0, 1);
  for (std::size_t n : {999u, 1000u}) {  // the reversal in place pairs the samples; odd n has a middle one
    std::vector<double> r, y;
    double x = 0;
    for (std::size_t i = 0; i < n; ++i) {
      r.push_back(x = 0.3 * x + e(rng));
      y.push_back(5.0 + 0.01 * static_cast<double>(i) + r.back());
    }
    const WhitenessTest a = ljung_box(r, 20);
    std::vector<double> scratch = r;
    const WhitenessTest b = ljung_box_in_place(scratch, 20);
    CHECK(b.q == a.q);
    CHECK(b.p_value == a.p_value);
    CHECK(b.lags == a.lags);
    CHECK(scratch != r);  // overwritten, as documented

    FitResult f, g;
    f.diagnostics.num_parameters = g.diagnostics.num_parameters = 3;
    fill_residual_diagnostics(f, r, y, true);
    scratch = r;
    fill_residual_diagnostics_in_place(g, scratch, y, true);
    CHECK(g.diagnostics.rss == f.diagnostics.rss);
    CHECK(g.diagnostics.rms == f.diagnostics.rms);
    CHECK(g.diagnostics.r2 == f.diagnostics.r2);
    CHECK(g.diagnostics.aic == f.diagnostics.aic);
    CHECK(g.diagnostics.bic == f.diagnostics.bic);
    CHECK(g.diagnostics.whiteness_p == f.diagnostics.whiteness_p);
    CHECK(g.diagnostics.whiteness_lags == f.diagnostics.whiteness_lags);
    CHECK(f.diagnostics.whiteness_lags == 20);
  }
  // Constant residuals: no whiteness statistic (p 1, no lags), in place as well.
  std::vector<double> flat(10, 2.0);
  CHECK(ljung_box_in_place(flat, 5).p_value == 1.0);
  CHECK(ljung_box_in_place(flat, 5).lags == 0);
}

TEST_CASE("the median sample interval counted without a buffer is the median of the intervals") {
  auto intervals_median = [](const std::vector<double>& t) {
    std::vector<double> d;
    for (std::size_t i = 1; i < t.size(); ++i) d.push_back(t[i] - t[i - 1]);
    return median(d);
  };
  // A regular 1 kHz clock: its intervals differ by the rounding of its instants alone (a few values).
  std::vector<double> regular;
  for (int i = 0; i < 100000; ++i) regular.push_back(-10.0 + i * 1e-3);
  CHECK(median_interval(regular) == intervals_median(regular));
  // Exactly 8 and then 9 distinct intervals (the second takes the buffer), of uneven counts.
  for (int kinds : {8, 9}) {
    std::vector<double> t = {0.0};
    for (int i = 0; i < 1001; ++i) t.push_back(t.back() + 1.0 + (i * 7 % kinds) * 0.125);
    std::vector<double> scratch(t.size() - 1);
    CHECK(median_interval(t, scratch) == intervals_median(t));
    CHECK(median_interval(t) == intervals_median(t));
  }
  // A jittery clock: every interval its own value.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(0.9e-3, 1.1e-3);
  std::vector<double> jittery = {0.0};
  for (int i = 0; i < 4000; ++i) jittery.push_back(jittery.back() + jitter(rng));
  CHECK(median_interval(jittery) == intervals_median(jittery));
  // An even number of intervals: the upper middle one, as median() takes it.
  CHECK(median_interval(std::vector<double>{0.0, 1.0, 3.0, 6.0, 10.0}) == 3.0);
  CHECK(median_interval(std::vector<double>{0.0, 1.0, 2.0, 4.0, 6.0}) == 2.0);
  CHECK(median_interval(std::vector<double>{5.0}) == 0.0);
}

TEST_CASE("the residuals' variance factor is 1 for white noise and (1 + phi) / (1 - phi) for AR(1)") {
  std::mt19937 rng(11);
  std::normal_distribution<double> e(0, 1);
  std::vector<double> white, ar;
  double x = 0;
  for (int i = 0; i < 20000; ++i) {
    white.push_back(e(rng));
    x = 0.8 * x + e(rng);
    ar.push_back(x);
  }
  CHECK(residual_variance_factor(white) < 1.1);
  CHECK(residual_variance_factor(ar) == Approx(9.0).epsilon(0.2));  // (1 + 0.8) / (1 - 0.8)
  CHECK(residual_variance_factor(std::vector<double>(50, 2.0)) == 1.0);
}

TEST_CASE("the median is the upper middle value, 0 for no values") {
  CHECK(median({3.0, 1.0, 2.0}) == 2.0);
  CHECK(median({4.0, 1.0, 3.0, 2.0}) == 3.0);
  CHECK(median({}) == 0.0);
  std::vector<double> v = {4.0, 1.0, 3.0, 2.0};
  CHECK(median_in_place(v) == 3.0);
}

TEST_CASE("linear interpolation holds the end values outside the table and is exact at knots") {
  const std::vector<double> xs{0.0, 1.0, 3.0}, ys{10.0, 20.0, 0.0};
  CHECK(interp_linear(xs, ys, -5.0) == 10.0);
  CHECK(interp_linear(xs, ys, 7.0) == 0.0);
  CHECK(interp_linear(xs, ys, 1.0) == 20.0);
  CHECK(interp_linear(xs, ys, 0.5) == Approx(15.0));
  CHECK(interp_linear(xs, ys, 2.0) == Approx(10.0));
  const std::vector<double> q{-1.0, 0.5, 2.0, 4.0};
  CHECK(interp_linear(xs, ys, q) == std::vector<double>{10.0, 15.0, 10.0, 0.0});
}
