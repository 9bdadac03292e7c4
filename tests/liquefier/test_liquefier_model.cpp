// The whole-record liquefier model: a store of melt with tau(q) = a q^b, fitted by output error
// over records that never settle, at a camera's 25 Hz and a load cell's 1 kHz.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdlib>
#include <random>

#include "synth_store.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/liquefier_model.hpp"
#include "tunekit/ident/step_analysis.hpp"

using namespace tunekit;
using tunekit::test::StoreTruth;
using tunekit::test::synth_store;

namespace {

double rel(double est, double truth) { return std::abs(est - truth) / std::abs(truth); }

bool covers(const fitting::Param& p, double truth) { return p.ci95_lo <= truth && truth <= p.ci95_hi; }

}  // namespace

TEST_CASE("the store's simulation converges: the automatic sub-steps agree with 64 sub-steps within 0.1 %") {
  const StoreTruth tr;
  for (double rate : {25.0, 1000.0}) {
    const auto s = synth_store(tr, rate, 20.0, 0.0, 3);
    const auto coarse = fitting::simulate_liquefier(s.rec.t, s.rec.u, tr.params(), tr.sensor);
    const auto fine = fitting::simulate_liquefier(s.rec.t, s.rec.u, tr.params(), tr.sensor, 64);
    double worst = 0;
    for (std::size_t i = 0; i < fine.size(); ++i) worst = std::max(worst, std::abs(coarse[i] - fine[i]) / 14.0);
    INFO("rate " << rate << " Hz");
    CHECK(worst < 1e-3);
  }
}

TEST_CASE("the store's sensitivities are the derivatives of its simulation (central differences)") {
  // Driven by the sampled input (steps as ramps across a sample interval) and by the commanded
  // track (steps at their exact instants, two points each).
  for (bool track : {false, true}) {
    for (auto sensor : {fitting::LiquefierSensor::flow, fitting::LiquefierSensor::pressure}) {
      for (double b : {-0.45, 0.0, 0.3}) {
        StoreTruth tr;
        tr.b = b;
        tr.sensor = sensor;
        tr.g = 1.7;
        const auto s = synth_store(tr, 50.0, 12.0, 0.0, 7);
        const std::vector<double>& tu = track ? s.rec.input_t : s.rec.t;
        const std::vector<double>& uu = track ? s.rec.input_u : s.rec.u;
        fitting::LiquefierParams p = tr.params();
        p.v0 = 0.6 * tr.volume(s.rec.u.front());
        // Off the sample grid: where a delayed breakpoint falls on a sample instant the discrete
        // model's derivative in theta is one-sided (its two sides differ by the discretisation).
        p.theta_s = 0.1037;
        const auto d = fitting::liquefier_sensitivities(s.rec.t, tu, uu, p, sensor, 3);
        const std::array<double fitting::LiquefierParams::*, 4> field{
            &fitting::LiquefierParams::a, &fitting::LiquefierParams::b, &fitting::LiquefierParams::theta_s,
            &fitting::LiquefierParams::v0};
        for (std::size_t k = 0; k < 4; ++k) {
          const double h = 1e-6 * std::max(1.0, std::abs(p.*field[k]));
          fitting::LiquefierParams pp = p, pm = p;
          pp.*field[k] += h;
          pm.*field[k] -= h;
          const auto yp = fitting::simulate_liquefier(s.rec.t, tu, uu, pp, sensor, 3);
          const auto ym = fitting::simulate_liquefier(s.rec.t, tu, uu, pm, sensor, 3);
          double worst = 0, scale = 0;
          for (std::size_t i = 0; i < d.size(); ++i) {
            const double fd = (yp[i] - ym[i]) / (2 * h);
            worst = std::max(worst, std::abs(fd - d[i][k]));
            scale = std::max(scale, std::abs(fd));
          }
          INFO((track ? "track" : "sampled") << ", sensor " << fitting::to_string(sensor) << " b " << b << " parameter "
                                             << k << ": worst " << worst << " of " << scale);
          CHECK(scale > 0);
          CHECK(worst <= 1e-5 * scale);
        }
      }
    }
  }
}

TEST_CASE("the linear store (b = 0) is the first-order response with tau = a") {
  StoreTruth tr;
  tr.a = 0.3;
  tr.b = 0;
  tr.theta_s = 0;
  std::vector<double> t, u;
  for (int i = 0; i < 400; ++i) {
    t.push_back(i * 0.01);
    u.push_back(i < 100 ? 2.0 : 5.0);
  }
  const auto y = fitting::simulate_liquefier(t, u, tr.params(), tr.sensor);
  // The input ramps over the sample interval 0.99..1.00 s: the response is the first-order
  // response to that ramp.
  for (int i = 150; i < 400; i += 50) {
    const double s = t[static_cast<std::size_t>(i)] - 0.99;
    const double expect = 2.0 + 3.0 - 3.0 * 0.3 / 0.01 * std::exp(-s / 0.3) * (std::exp(0.01 / 0.3) - 1);
    CHECK(y[static_cast<std::size_t>(i)] == Approx(expect).epsilon(1e-9));
  }
}

TEST_CASE("a never-settled staircase of the nonlinear store gives a, b and theta back at 25 Hz and at 1 kHz") {
  // At 25 Hz and 2 % noise a minute of record leaves a standard error of a of about 3.5 %: the
  // 3 % bound needs about eight minutes (1.3 %); at 1 kHz a minute leaves about 0.6 %.
  const StoreTruth tr;
  for (double rate : {25.0, 1000.0}) {
    const auto s = synth_store(tr, rate, rate < 100 ? 480.0 : 60.0, 0.02, 11);
    const auto m = fitting::fit_liquefier_model(s.rec);
    INFO("rate " << rate << " Hz: a " << m.fit.derived.front().value << " b " << m.fit.value("b") << " theta "
                 << m.fit.value("theta_s"));
    CHECK_FALSE(m.linear_chosen);
    CHECK(rel(m.fit.derived.front().value, tr.a) < 0.03);
    CHECK(std::abs(m.fit.value("b") - tr.b) < 0.05);
    CHECK(rel(m.fit.value("theta_s"), tr.theta_s) < 0.10);
    CHECK(m.fit.param("b").ci95_method == "profile-likelihood");
    CHECK(m.fit.param("theta_s").ci95_method == "profile-likelihood");
  }
}

TEST_CASE("a load cell's pressure record of the store is fitted with the stored volume as the sensed quantity") {
  StoreTruth tr;
  tr.sensor = fitting::LiquefierSensor::pressure;
  tr.g = 2.0;
  tr.c = 0.5;
  const auto s = synth_store(tr, 200.0, 40.0, 0.02, 5);
  const auto m = fitting::fit_liquefier_model(s.rec);
  CHECK(rel(m.fit.derived.front().value, tr.a) < 0.03);
  CHECK(std::abs(m.fit.value("b") - tr.b) < 0.05);
  CHECK(rel(m.fit.value("g"), tr.g) < 0.03);
}

TEST_CASE("a linear liquefier's record chooses the linear model: b's interval holds 0") {
  StoreTruth tr;
  tr.a = 0.3;
  tr.b = 0.0;
  const auto s = synth_store(tr, 100.0, 40.0, 0.02, 9);
  const auto m = fitting::fit_liquefier_model(s.rec);
  CHECK(m.linear_chosen);
  CHECK(m.f_statistic <= m.f_threshold);
  CHECK(m.fit.param("b").fixed);
  CHECK(rel(m.fit.value("tau_ref_s"), 0.3) < 0.02);
}

TEST_CASE("rises slower than falls are one store: one model explains both directions to the noise") {
  // b = -0.45: filling towards a high flow starts at the low flow's long time constant, draining
  // from it starts fast. The per-step first-order fits see rises slower than falls; a single
  // linear model cannot follow both, the store does.
  const StoreTruth tr;
  const auto s = synth_store(tr, 100.0, 40.0, 0.02, 21, {4, 14});
  ident::StepAnalysisOptions so;
  const auto steps = ident::analyze_steps(s.rec.t, s.rec.u, s.rec.y, so);
  double rise = 0, fall = 0;
  int nr = 0, nf = 0;
  for (const auto& st : steps.steps) {
    if (!st.fit) continue;
    (st.step.rising() ? rise : fall) += st.fit->value("tau_s");
    (st.step.rising() ? nr : nf) += 1;
  }
  REQUIRE(nr > 3);
  REQUIRE(nf > 3);
  CHECK(rise / nr > 1.1 * (fall / nf));
  const auto m = fitting::fit_liquefier_model(s.rec);
  double mean = 0;
  for (double v : s.clean) mean += v;
  const double sigma = 0.02 * mean / static_cast<double>(s.clean.size());
  CHECK_FALSE(m.linear_chosen);
  CHECK(m.fit.diagnostics.rms < 1.25 * sigma);
  CHECK(std::abs(m.fit.value("b") - tr.b) < 0.05);
  // The linear model misses the asymmetry: its residual sum of squares is far above the store's.
  CHECK(m.f_statistic > 100 * m.f_threshold);
}

namespace {

/// Coverage of the 95 % intervals of a, b and theta over `draws` records at `rate` Hz (40 s,
/// 2 % noise); TUNEKIT_STORE_DRAWS overrides the count. 200 draws: 90-98 %; fewer: the nominal
/// 95 % within three binomial standard deviations. TUNEKIT_STORE_SAMPLED_INPUT=1 drops the
/// commanded track (the input known at the samples only), for the comparison in
/// docs/liquefier-model.md; at 25 Hz that run falls short of 90 %.
void check_coverage(double rate, int draws) {
  if (const char* env = std::getenv("TUNEKIT_STORE_DRAWS")) draws = std::max(10, std::atoi(env));
  const bool sampled = std::getenv("TUNEKIT_STORE_SAMPLED_INPUT") != nullptr;
  const StoreTruth tr;
  int ca = 0, cb = 0, ct = 0;
  for (int d = 0; d < draws; ++d) {
    auto s = synth_store(tr, rate, 40.0, 0.02, 1000u + static_cast<unsigned>(d));
    if (sampled) {
      s.rec.input_t.clear();
      s.rec.input_u.clear();
    }
    const auto m = fitting::fit_liquefier_model(s.rec);
    ca += covers(m.nonlinear.derived.front(), tr.a);
    cb += covers(m.nonlinear.param("b"), tr.b);
    ct += covers(m.nonlinear.param("theta_s"), tr.theta_s);
  }
  const double n = draws;
  const double spread = draws >= 200 ? 0.0 : 3 * std::sqrt(0.95 * 0.05 / n);
  const double lo = std::min(0.90, 0.95 - spread), hi = std::max(0.98, std::min(1.0, 0.95 + spread));
  INFO((sampled ? "sampled input, " : "")
       << "rate " << rate << " Hz, draws " << draws << ": a " << ca / n << " b " << cb / n << " theta " << ct / n);
  CHECK(ca / n >= lo);
  CHECK(ca / n <= hi);
  CHECK(cb / n >= lo);
  CHECK(cb / n <= hi);
  CHECK(ct / n >= lo);
  CHECK(ct / n <= hi);
}

}  // namespace

// The figures in docs/liquefier-model.md are from 200 draws (TUNEKIT_STORE_DRAWS=200); the
// defaults keep the tests short.
TEST_CASE("the 95 % intervals of a, b and theta cover the truth in 90-98 % of draws at 25 Hz", "[repeats]") {
  check_coverage(25.0, 24);
}

TEST_CASE("the 95 % intervals of a, b and theta cover the truth in 90-98 % of draws at 1 kHz", "[repeats]") {
  check_coverage(1000.0, 6);
}

TEST_CASE("without the commanded track the sampled input alone gives a, b and theta back") {
  // A record whose input is known only at the sensor's instants: each step becomes a ramp across
  // its sample interval, its instant known to a sample interval. At 1 kHz that is 1 ms and the
  // bounds hold; at 25 Hz the 40 ms of every step add an error of their own (the residuals
  // correlate, the intervals widen by the variance factor), and the truth lies in the intervals.
  const StoreTruth tr;
  for (double rate : {25.0, 1000.0}) {
    auto s = synth_store(tr, rate, 60.0, 0.02, 11);
    s.rec.input_t.clear();
    s.rec.input_u.clear();
    const auto m = fitting::fit_liquefier_model(s.rec);
    INFO("rate " << rate << " Hz: a " << m.fit.derived.front().value << " b " << m.fit.value("b") << " theta "
                 << m.fit.value("theta_s") << ", variance factor " << m.variance_factor);
    CHECK_FALSE(m.linear_chosen);
    if (rate > 100) {
      CHECK(rel(m.fit.derived.front().value, tr.a) < 0.03);
      CHECK(std::abs(m.fit.value("b") - tr.b) < 0.05);
      CHECK(rel(m.fit.value("theta_s"), tr.theta_s) < 0.10);
    } else {
      CHECK(m.variance_factor > 1.5);
      CHECK(covers(m.fit.derived.front(), tr.a));
      CHECK(covers(m.fit.param("b"), tr.b));
      CHECK(covers(m.fit.param("theta_s"), tr.theta_s));
    }
  }
}

TEST_CASE("a record that starts with an empty liquefier holds the start volume at 0 and fits the rest") {
  // The output does not depend on V0 at its bound 0: it is held there for the covariance (the
  // fit is solved once) and reported fixed.
  const StoreTruth tr;
  auto s = synth_store(tr, 100.0, 40.0, 0.0, 41);
  fitting::LiquefierParams p = tr.params();
  p.v0 = 0.0;
  const auto clean = fitting::simulate_liquefier(s.rec.t, s.rec.input_t, s.rec.input_u, p, tr.sensor, 8);
  std::mt19937 rng(41);
  std::normal_distribution<double> noise(0.0, 0.002 * 9.0);
  for (std::size_t i = 0; i < clean.size(); ++i) s.rec.y[i] = clean[i] + noise(rng);
  const auto m = fitting::fit_liquefier_model(s.rec);
  INFO("a " << m.fit.derived.front().value << " b " << m.fit.value("b") << " V0 " << m.fit.value("V0"));
  CHECK(m.fit.param("V0").fixed);
  CHECK(m.fit.value("V0") == 0.0);
  CHECK(m.nonlinear.param("V0").fixed);
  CHECK(rel(m.fit.derived.front().value, tr.a) < 0.05);
  CHECK(std::abs(m.fit.value("b") - tr.b) < 0.05);
  CHECK(m.fit.param("tau_ref_s").std_error > 0);
}

TEST_CASE("a record that cannot carry the model is refused with a plain reason") {
  fitting::LiquefierRecord r;
  for (int i = 0; i < 50; ++i) {
    r.t.push_back(i * 0.01);
    r.u.push_back(3.0);
    r.y.push_back(3.0 + 0.01 * (i % 3));
  }
  CHECK_THROWS_AS(fitting::fit_liquefier_model(r), InputError);
  r.u[10] = -1;
  CHECK_THROWS_WITH(fitting::fit_liquefier_model(r), Catch::Contains("negative"));
  r.u[10] = 3.0;
  r.u[20] = 4.0;
  r.input_t = {0.0, 0.2, 0.1};
  r.input_u = {3.0, 3.0, 4.0};
  CHECK_THROWS_WITH(fitting::fit_liquefier_model(r), Catch::Contains("goes back"));
  r.input_u.pop_back();
  CHECK_THROWS_WITH(fitting::fit_liquefier_model(r), Catch::Contains("differ in length"));
}

TEST_CASE("a dead time that ends at its bound 0 has no interval below 0") {
  // The response leads its commanded input by 10 ms (a photo placed 0.2 mm off at 20 mm/s does
  // that): the best dead time is 0, at its bound. Its interval was value +- t s, half of it
  // negative; every interval now ends at its parameter's domain.
  StoreTruth tr;
  tr.theta_s = 0;
  auto s = synth_store(tr, 100.0, 40.0, 0.002, 43);
  for (double& ti : s.rec.input_t) ti += 0.010;
  fitting::LiquefierFitOptions o;
  o.profile = false;  // the Wald intervals alone (the profile's end at a bound is its own)
  const auto m = fitting::fit_liquefier_model(s.rec, o);
  const auto& theta = m.fit.param("theta_s");
  INFO("theta " << theta.value << " [" << theta.ci95_lo << ", " << theta.ci95_hi << "]");
  CHECK(theta.value < 1e-6);
  CHECK(theta.ci95_lo >= 0);
  CHECK(theta.ci95_hi > theta.value);
  CHECK(m.fit.param("tau_ref_s").ci95_lo > 0);
}
