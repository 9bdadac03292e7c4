// The liquefier chirp and its analysis sized from the expected corner 1/(2 pi tau).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "tunekit/core/error.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit::protocols;
using namespace tunekit::machine;
using namespace tunekit::firmware;

TEST_CASE("the chirp plan brackets the corner and puts several Welch bins below it") {
  for (double tau : {0.05, 0.45, 2.0}) {
    INFO("tau " << tau);
    const auto p = plan_liquefier_chirp(tau);
    const double fc = 1 / (2 * std::numbers::pi * tau);
    CHECK(p.corner_hz == Approx(fc));
    CHECK(p.freq_min_hz <= fc / 5);
    CHECK(p.freq_max_hz >= std::min(5 * fc, 5.0) - 1e-12);  // up to the staircase's reach (5 Hz at 20 ms)
    CHECK(p.freq_max_hz <= 5.0 + 1e-12);
    CHECK(p.duration_s * fc >= 20 - 1e-9);
    CHECK(p.settle_s >= 10 * tau - 1e-12);
    CHECK(p.analysis_start_s < p.settle_s);
    // At 200 Hz: bins at most a third of the corner apart, so at least three below it.
    const double bin = 200.0 / static_cast<double>(p.welch_segment_samples(200));
    CHECK(fc / bin >= 3);
  }
  // The numbers docs/calibrate.md gives for tau = 0.45 s.
  const auto p = plan_liquefier_chirp(0.45);
  CHECK(p.freq_min_hz == Approx(0.0354).epsilon(1e-3));
  CHECK(p.freq_max_hz == Approx(1.768).epsilon(1e-3));
  CHECK(p.duration_s == Approx(56.55).epsilon(1e-3));
  CHECK(p.welch_segment_samples(200) == 2048);
  CHECK_THROWS_AS(plan_liquefier_chirp(0), tunekit::InputError);
  CHECK_THROWS_AS(plan_liquefier_chirp(std::nan("")), tunekit::InputError);
  CHECK_THROWS_AS(plan_liquefier_chirp(0.45, -1), tunekit::InputError);
}

TEST_CASE("the chirp protocol sizes itself from expected_tau_s unless a parameter is given") {
  const auto profile = tunekit::sim::builtin_sim_profile();
  const auto plan = plan_liquefier_chirp(0.3);
  const auto e = build_experiment("liquefier-chirp", {{"expected_tau_s", 0.3}}, "x", profile, Dialect());
  CHECK(e.params.at("freq_min_hz") == plan.freq_min_hz);
  CHECK(e.params.at("freq_max_hz") == plan.freq_max_hz);
  CHECK(e.params.at("duration_s") == plan.duration_s);
  CHECK(e.params.at("settle_s") == plan.settle_s);
  CHECK(e.estimated_duration_s > plan.settle_s + plan.duration_s);
  const auto given =
      build_experiment("liquefier-chirp", {{"expected_tau_s", 0.3}, {"duration_s", 30}}, "x", profile, Dialect());
  CHECK(given.params.at("duration_s") == 30);
  CHECK(given.params.at("freq_min_hz") == plan.freq_min_hz);
  const auto plain = build_experiment("liquefier-chirp", {}, "x", profile, Dialect());
  CHECK(plain.params.at("duration_s") == 20);
  CHECK_THROWS_AS(build_experiment("liquefier-chirp", {{"expected_tau_s", -1}}, "x", profile, Dialect()),
                  tunekit::InputError);
}
