// Intervals that mean what they say: profile likelihood on Cross-WLF's WLF ridge (a Monte-Carlo
// coverage test with known truth), the identifiable quantities with their own intervals, and no
// nulls where numbers belong (exact fits, intervals on a bound, model comparison reasons).
#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <functional>
#include <random>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/least_squares.hpp"
#include "tunekit/fitting/profile_likelihood.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/fitting/viscosity.hpp"

using namespace tunekit::fitting;
using tunekit::test::run_cli;
using tunekit::test::write_scratch;

namespace {

// Truth on the ridge: D2 328 K, A1 24.5 (A2 51.6 K held as by default), three temperatures.
CrossWlfParams ridge_truth() {
  CrossWlfParams c;
  c.n = 0.35;
  c.tau_star_Pa = 5e4;
  c.D2_K = 328;
  c.A1 = 24.5;
  c.A2_K = 51.6;
  c.D3_K_per_Pa = 0;
  // eta0 = 2000 Pa.s at 220 degC.
  const double x = 493.15 - c.D2_K;
  c.D1_Pa_s = 2000 * std::exp(c.A1 * x / (c.A2_K + x));
  return c;
}

RheologyData ridge_draw(const CrossWlfParams& c, std::mt19937& rng, double noise) {
  std::normal_distribution<double> z(0, noise);
  RheologyData d;
  for (double degc : {200.0, 220.0, 240.0})
    for (int i = 0; i < 12; ++i) {
      const double g = std::pow(10.0, i * 4.0 / 11);
      const double T = degc + kKelvinOffset;
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(cross_wlf_viscosity(c, g, T) * std::exp(z(rng)));
    }
  return d;
}

// Every number under `j` is a number: no null, except where no number exists -- a held
// parameter's interval, and the whiteness test of residuals that have no order (whiteness_lags 0).
void check_no_nulls(const nlohmann::json& j, const std::string& path = "") {
  if (j.is_null()) {
    FAIL_CHECK("null at " << path);
    return;
  }
  if (j.is_object()) {
    if (j.value("fixed", false)) return;
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (it.key() == "whiteness_p" && j.value("whiteness_lags", -1) == 0) continue;
      check_no_nulls(it.value(), path + "/" + it.key());
    }
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) check_no_nulls(j[i], path + "/" + std::to_string(i));
  }
}

}  // namespace

TEST_CASE("Cross-WLF at three temperatures: 95 % intervals of D2 and A1 cover the truth in 90-99 % of 200 draws",
          "[repeats]") {
  const auto truth = ridge_truth();
  std::mt19937 rng(20261123);
  ViscosityFitOptions o;
  o.model = ViscosityModel::cross_wlf;
  int draws = 0, cover_d2 = 0, cover_a1 = 0, profiled = 0, wald_cover_d2 = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < 200; ++k) {
    const auto data = ridge_draw(truth, rng, 0.03);
    FitResult fit;
    try {
      fit = fit_viscosity(data, o);
    } catch (const tunekit::Error& e) {
      FAIL_CHECK("draw " << k << ": " << e.message());
      continue;
    }
    ++draws;
    const auto& d2 = fit.param("D2_K");
    const auto& a1 = fit.param("A1");
    if (d2.ci95_lo <= truth.D2_K && truth.D2_K <= d2.ci95_hi) ++cover_d2;
    if (a1.ci95_lo <= truth.A1 && truth.A1 <= a1.ci95_hi) ++cover_a1;
    if (d2.ci95_method == "profile-likelihood") ++profiled;
    // The linearised interval for comparison (what the fit reported before profiles).
    const double t = t_multiplier(0.95, fit.diagnostics.num_observations - fit.diagnostics.num_parameters);
    if (std::abs(d2.value - truth.D2_K) <= t * d2.std_error) ++wald_cover_d2;
  }
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  INFO("draws " << draws << ", D2 covered " << cover_d2 << ", A1 covered " << cover_a1 << ", D2 profiled " << profiled
                << ", Wald D2 would cover " << wald_cover_d2 << ", " << secs << " s");
  REQUIRE(draws == 200);
  CHECK(cover_d2 >= 180);
  CHECK(cover_d2 <= 198);
  CHECK(cover_a1 >= 180);
  CHECK(cover_a1 <= 198);
  // On this ridge the profile is what the fit chooses for D2.
  CHECK(profiled >= 190);
}

TEST_CASE("the WLF ridge is named, and what the data determine is reported with its own interval") {
  const auto truth = ridge_truth();
  std::mt19937 rng(7);
  const auto data = ridge_draw(truth, rng, 0.03);
  ViscosityFitOptions o;
  o.model = ViscosityModel::cross_wlf;
  const auto fit = fit_viscosity(data, o);
  bool named = false;
  for (const auto& w : fit.warnings)
    named = named ||
            (w.find("D1_Pa_s, D2_K, A1 are not separately identifiable from 3 temperatures") != std::string::npos &&
             w.find("fix D2_K at the polymer's glass transition") != std::string::npos);
  CHECK(named);
  // eta0 at each measured temperature: a derived quantity whose interval covers the truth and is tight.
  REQUIRE(fit.derived.size() == 6);  // eta0 and eta at the median shear rate, per temperature
  int eta0s = 0;
  for (const auto& q : fit.derived) {
    if (q.name.rfind("eta0_Pa_s_at_", 0) != 0) continue;
    ++eta0s;
    const double T = std::stod(q.name.substr(std::string("eta0_Pa_s_at_").size()));
    const double eta0 = cross_wlf_zero_shear(truth, T);
    INFO(q.name << " " << q.value << " [" << q.ci95_lo << ", " << q.ci95_hi << "], truth " << eta0);
    CHECK(q.ci95_lo <= eta0);
    CHECK(q.ci95_hi >= eta0);
    CHECK(q.ci95_hi / q.ci95_lo < 1.5);
  }
  CHECK(eta0s == 3);
  // The correlation matrix: the ridge shows as |r| close to 1 between D2 and A1.
  const auto corr = correlation_json(fit);
  REQUIRE(corr["parameters"].size() == 5);
  std::size_t i2 = 0, ia = 0;
  for (std::size_t i = 0; i < corr["parameters"].size(); ++i) {
    if (corr["parameters"][i] == "D2_K") i2 = i;
    if (corr["parameters"][i] == "A1") ia = i;
  }
  CHECK(std::abs(corr["matrix"][i2][ia].get<double>()) > 0.99);
  CHECK(corr["matrix"][i2][i2].get<double>() == Approx(1.0));
  // Holding D2 at its true value (the glass-transition advice) closes the ridge: no warning,
  // and A1's interval covers the truth.
  o.fixed["D2_K"] = truth.D2_K;
  const auto held = fit_viscosity(data, o);
  for (const auto& w : held.warnings) CHECK(w.find("not separately identifiable") == std::string::npos);
  CHECK(held.param("A1").ci95_lo <= truth.A1);
  CHECK(held.param("A1").ci95_hi >= truth.A1);
}

TEST_CASE("profile intervals equal the Student-t interval for a model linear in its parameters") {
  // y = a + b x with noise: the profile of b is exactly the Wald interval.
  std::mt19937 rng(3);
  std::normal_distribution<double> z(0, 0.1);
  std::vector<double> x, y;
  for (int i = 0; i < 20; ++i) x.push_back(i), y.push_back(1 + 0.5 * i + z(rng));
  LsqProblem prob;
  prob.params = {{"a", "1", 0.0}, {"b", "1", 0.0}};
  prob.num_residuals = 20;
  prob.observed = y;
  prob.residuals_are_time_ordered = false;
  prob.residuals = [&](const double* p, double* r) {
    for (int i = 0; i < 20; ++i) r[i] = p[0] + p[1] * x[i] - y[i];
    return true;
  };
  const auto fit = solve_least_squares("line", prob);
  const auto pi = profile_interval(prob, fit, 1);
  const auto& b = fit.params[1];
  CHECK(pi.lo == Approx(b.ci95_lo).margin(0.02 * (b.ci95_hi - b.ci95_lo)));
  CHECK(pi.hi == Approx(b.ci95_hi).margin(0.02 * (b.ci95_hi - b.ci95_lo)));
  CHECK_FALSE(pi.lo_at_bound);
  CHECK_FALSE(pi.hi_at_bound);
  // apply_profile_intervals keeps the Wald interval here (no correlation, no curvature, no bound).
  auto copy = fit;
  apply_profile_intervals(prob, copy);
  CHECK(copy.params[1].ci95_method == "wald");
}

TEST_CASE("a Newtonian data set selects the Newtonian model with a finite AIC") {
  RheologyData d;
  for (int i = 0; i < 10; ++i) {
    d.shear_rate_1_s.push_back(std::pow(10.0, i * 0.4));
    d.viscosity_Pa_s.push_back(1500.0);
    d.temperature_K.push_back(473.15);
  }
  const auto cmp = compare_viscosity_models(d, default_candidates(d));
  CHECK(cmp.best == "newtonian");
  for (const auto& e : cmp.entries) {
    INFO(e.model << ": " << e.error);
    if (e.ok) {
      CHECK(std::isfinite(e.aic));
      CHECK(std::isfinite(e.bic));
      CHECK(std::isfinite(e.akaike_weight));
    } else {
      CHECK(!e.error.empty());
    }
  }
  const auto& nf = cmp.fits.front();
  CHECK(nf.value("eta0_Pa_s") == Approx(1500).epsilon(1e-9));
  CHECK(std::isfinite(nf.diagnostics.aic));
  CHECK(nf.diagnostics.r2 == 1.0);
  // Every fitted candidate (Cross and Carreau-Yasuda end on bounds here) reports finite intervals.
  check_no_nulls(to_json(cmp));
  for (const auto& f : cmp.fits)
    if (!f.params.empty()) check_no_nulls(to_json(f));
}

TEST_CASE("rheo: no nulls where numbers belong, and every could-not-fit reason filled in") {
  const std::string head = "shear_rate (1/s),viscosity (Pa.s),temperature (degC)\n";
  SECTION("an exact Newtonian fit wins --model auto with a finite AIC") {
    std::string rows;
    for (int i = 0; i < 10; ++i) rows += std::to_string(std::pow(10.0, i * 0.4)) + ",1500,200\n";
    const auto f = write_scratch("rheo_newtonian_exact.csv", head + rows);
    const auto r = run_cli({"rheo", f, "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["results"]["model"] == "newtonian");
    CHECK(j["results"]["diagnostics"]["aic"].is_number());
    CHECK(j["results"]["model_comparison"]["best"] == "newtonian");
    check_no_nulls(j["results"]);
  }
  SECTION("a model comparison where nothing fits lists a reason for every model") {
    const auto f = write_scratch("rheo_one_row.csv", head + "10,1500,200\n");
    const auto r = run_cli({"rheo", f});
    CHECK(r.code != 0);
    CHECK(r.err.find("no viscosity model could be fitted (newtonian: ") != std::string::npos);
    CHECK(r.err.find(": ;") == std::string::npos);
    CHECK(r.err.find(": )") == std::string::npos);
    CHECK(r.err.find("data points for") != std::string::npos);
  }
  SECTION("intervals of parameters that end on a bound stay numbers") {
    // Newtonian-looking data fitted with Cross: tau* runs to its bound, its ln interval is wide.
    std::string rows;
    for (int i = 0; i < 8; ++i)
      rows += std::to_string(std::pow(10.0, i * 0.5)) + "," + std::to_string(800 + 3 * (i % 2)) + ",200\n";
    const auto f = write_scratch("rheo_cross_on_bound.csv", head + rows);
    const auto r = run_cli({"rheo", f, "--model", "cross", "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    check_no_nulls(j["results"]);
    const auto& ts = j["results"]["params"]["tau_star_Pa"];
    CHECK(ts["ci95"][1].get<double>() <= 1e8);
    CHECK(ts["ci95"][0].get<double>() > 0);
  }
}

TEST_CASE("nozzle --fit: R2 is a number when the pressures do not vary") {
  const auto f = write_scratch("nozzle_flat.csv",
                               "flow (mm3/s),pressure (MPa),temperature (degC)\n1.5,4.0,405\n3,4.0,405\n"
                               "6,4.0,405\n4.5,4.0,405\n");
  const auto r = run_cli({"nozzle", "--fit", f, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["results"]["diagnostics"]["r2"].is_number());
  CHECK(j["results"]["diagnostics"]["aic"].is_number());
  CHECK(r.err.find("do not vary") != std::string::npos);
}
