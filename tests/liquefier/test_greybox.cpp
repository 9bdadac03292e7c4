// Seed 001 appendix C grey-box model: transfer function, identifiable combinations, and an
// output-error fit that recovers the coefficients once C_f is fixed and refuses all four.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/greybox.hpp"

using namespace tunekit;

TEST_CASE("appendix C grey-box: unit DC gain, three identifiable combinations, fit with C_f fixed") {
  const fitting::GreyBoxParams truth{2.0, 1.0, 0.5, 0.8};
  const auto tf = fitting::greybox_tf(truth);
  CHECK(tf.dc_gain() == Approx(1.0));
  const auto c = fitting::greybox_combinations(truth);
  CHECK(c.tau_t_s == Approx(0.5));
  CHECK(c.tau_f_s == Approx(0.4));
  CHECK(c.tau_n_s == Approx(0.8));
  // Scaling all four coefficients leaves the response unchanged: only the combinations matter.
  const auto scaled = fitting::greybox_tf({6.0, 3.0, 1.5, 2.4});
  for (double f : {0.01, 0.3, 2.0}) CHECK(std::abs(scaled.response(f) - tf.response(f)) < 1e-12);

  const double dt = 0.02;
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> coin(0, 1);
  std::normal_distribution<double> noise(0, 0.005);
  std::vector<double> u;
  double level = 0;
  for (int i = 0; i < 1500; ++i) {
    if (i % 60 == 0) level = coin(rng) ? 1.0 : 0.0;
    u.push_back(level);
  }
  auto y = fitting::greybox_tf(truth, 1.3).simulate_zoh(u, dt);
  for (auto& v : y) v += 0.2 + noise(rng);
  fitting::GreyBoxFitOptions o;
  o.C_f = 2.0;
  const auto fit = fitting::fit_greybox_output_error(u, y, dt, o);
  for (auto [name, value] : {std::pair{"C_t", 1.0}, {"D_t", 0.5}, {"D_n", 0.8}, {"K", 1.3}, {"y0", 0.2}}) {
    const auto& p = fit.param(name);
    INFO(name << " = " << p.value << " [" << p.ci95_lo << ", " << p.ci95_hi << "]");
    CHECK(p.value == Approx(value).epsilon(0.05));
  }
  CHECK(fit.param("C_f").fixed);
  REQUIRE_FALSE(fit.warnings.empty());
  CHECK(fit.warnings.back().find("tau_t") != std::string::npos);
  // All four free: the scale is not identifiable.
  o.fix_C_f = false;
  CHECK_THROWS_AS(fitting::fit_greybox_output_error(u, y, dt, o), FitError);
}
