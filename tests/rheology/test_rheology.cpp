// Melt rheology and nozzle pressure: Holtrup 2019 check values (datasets/rheology/check_values.csv),
// round trips of the fits from default bounds, model comparison, TTS and the inverse nozzle fit.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/viscosity.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"

using namespace tunekit::fitting;

namespace {

const CrossWlfParams& peek() { return cross_wlf_material("PEEK").params; }

void check_within_ci(const FitResult& fit, const std::string& name, double truth) {
  const auto& p = fit.param(name);
  INFO(name << " = " << p.value << " [" << p.ci95_lo << ", " << p.ci95_hi << "], truth " << truth);
  CHECK(p.ci95_lo <= truth);
  CHECK(p.ci95_hi >= truth);
}

}  // namespace

TEST_CASE("PEEK Cross-WLF at 400 degC and 1000 1/s: both temperature conventions") {
  // check_values.csv: 346.45 Pa.s with +273 (the seed's code), 345.96 Pa.s with +273.15.
  const double thesis = cross_wlf_viscosity(peek(), 1000, celsius_to_kelvin(400, kKelvinOffsetThesis));
  const double si = cross_wlf_viscosity(peek(), 1000, celsius_to_kelvin(400));
  CHECK(thesis == Approx(346.45).epsilon(2e-5));
  CHECK(si == Approx(345.96).epsilon(2e-5));
  CHECK(celsius_to_kelvin(400) - celsius_to_kelvin(400, kKelvinOffsetThesis) == Approx(0.15));
  // The appendix A closed form (with its own constants) agrees with the general model.
  const double T = 673.0, g = 1000;
  const double e = std::exp((-36.041 * T + 14529.92915) / (T - 351.55));
  CHECK(thesis == Approx(2.89808e16 * e / (3300099.99695341 * std::pow(g * e, 0.5734) + 1.0)).epsilon(1e-6));
}

TEST_CASE("power-law fits of PEEK Cross-WLF over 600-950 1/s (Holtrup 2019 sec. 5.2.3)") {
  const auto spec = ViscositySpec::from_cross_wlf(peek());
  struct Row {
    double degc, K, n;
  };
  for (const Row r : {Row{390, 10114, 0.5257}, Row{405, 7988, 0.5392}, Row{450, 4165, 0.5793}}) {
    const auto fit = fit_power_law_window(spec, celsius_to_kelvin(r.degc, kKelvinOffsetThesis), 600, 950, 50);
    INFO(r.degc << " degC");
    CHECK(fit.value("K_Pa_s_n") == Approx(r.K).epsilon(0.002));
    CHECK(fit.value("n") == Approx(r.n).epsilon(0.002));
  }
  // An inverted window is refused.
  CHECK_THROWS_AS(fit_power_law_window(spec, 663, 950, 600), tunekit::InputError);
}

TEST_CASE("Boles pressure drop: appendix F example and the 405 degC operating point") {
  NozzleGeometry f;
  f.d_m = 0.6e-3;
  f.l_m = 4e-3;
  f.cone_half_angle_rad = std::numbers::pi / 4;
  CHECK(boles_dp(10114, 0.51, 20e-9, f) * 1e-6 == Approx(12.164).epsilon(5e-4));

  NozzleGeometry g;  // Table 5.3 regular nozzle: 30 deg half angle
  const auto pl = holtrup_peek_power_law(405);
  CHECK(boles_dp(pl.K_Pa_s_n, pl.n, 3e-9, g) * 1e-6 == Approx(4.980).epsilon(2e-3));
}

TEST_CASE("pressure-drop models agree where they must") {
  NozzleGeometry g;
  const double mu = 500, Q = 3e-9;
  // A power-law fluid with n = 1 in a capillary is Hagen-Poiseuille.
  CHECK(power_law_capillary_dp(mu, 1.0, Q, g) == Approx(hagen_poiseuille_dp(mu, Q, g)).epsilon(1e-12));
  // Bellini's three zones for n = 1 equal Hagen-Poiseuille of the capillary plus the melt room plus the cone.
  NozzleGeometry g2 = g;
  g2.melt_length_m = 1e-12;
  const double cap_only = bellini_dp(mu, 1.0, Q, g2);
  CHECK(cap_only > hagen_poiseuille_dp(mu, Q, g));
  // The capillary zone of Bellini equals the power-law capillary model for any n.
  const double n = 0.54, K = 8000;
  NozzleGeometry long_land = g2, short_land = g2;
  long_land.l_m = 8e-3;
  short_land.l_m = 4e-3;
  CHECK(bellini_dp(K, n, Q, long_land) - bellini_dp(K, n, Q, short_land) ==
        Approx(power_law_capillary_dp(K, n, Q, long_land) - power_law_capillary_dp(K, n, Q, short_land)).epsilon(1e-9));
  // Bellini underestimates Boles (the seed: by about 1.5x for PEEK in the regular nozzle).
  const auto pl = holtrup_peek_power_law(405);
  const double ratio = boles_dp(pl.K_Pa_s_n, pl.n, Q, g) / bellini_dp(pl.K_Pa_s_n, pl.n, Q, g);
  CHECK(ratio > 1.1);
  CHECK(ratio < 2.5);
  // dP/dQ of a power-law model is n dP / Q.
  const double h = 1e-6 * Q;
  CHECK(pressure_drop_slope(PressureModel::boles, K, n, Q, g) ==
        Approx((boles_dp(K, n, Q + h, g) - boles_dp(K, n, Q - h, g)) / (2 * h)).epsilon(1e-5));
  CHECK_THROWS_AS(validate(NozzleGeometry{6e-3, 4e-3, 0.5, 5e-3, 1e-2}), tunekit::InputError);
}

TEST_CASE("Cross-WLF round trip: three temperatures, 3 % noise, default bounds, no start values") {
  RheologyData d;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.03);
  for (double degc : {380.0, 400.0, 420.0})
    for (int i = 0; i < 20; ++i) {
      const double g = std::pow(10.0, i * 4.0 / 19);
      const double T = celsius_to_kelvin(degc);
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(cross_wlf_viscosity(peek(), g, T) * std::exp(noise(rng)));
    }
  ViscosityFitOptions o;
  o.model = ViscosityModel::cross_wlf;
  const auto fit = fit_viscosity(d, o);
  CHECK(fit.model == "cross-wlf");
  CHECK(fit.diagnostics.converged);
  check_within_ci(fit, "n", peek().n);
  check_within_ci(fit, "tau_star_Pa", peek().tau_star_Pa);
  check_within_ci(fit, "D1_Pa_s", peek().D1_Pa_s);
  check_within_ci(fit, "D2_K", peek().D2_K);
  check_within_ci(fit, "A1", peek().A1);
  CHECK(fit.param("A2_K").fixed);
  CHECK(fit.param("D3_K_per_Pa").fixed);
  CHECK(fit.diagnostics.rms == Approx(0.03).epsilon(0.3));
  // The fitted model reproduces the check value within the data's noise.
  CHECK(spec_from_fit(fit).viscosity(1000, celsius_to_kelvin(400)) == Approx(345.96).epsilon(0.03));
}

TEST_CASE("temperature-dependent models refuse data at a single temperature") {
  RheologyData d;
  for (int i = 0; i < 10; ++i) {
    d.shear_rate_1_s.push_back(std::pow(10.0, i * 0.4));
    d.viscosity_Pa_s.push_back(cross_wlf_viscosity(peek(), d.shear_rate_1_s.back(), 673.15));
    d.temperature_K.push_back(673.15);
  }
  ViscosityFitOptions o;
  CHECK_THROWS_AS(fit_viscosity(d, o), tunekit::InputError);
  o.model = ViscosityModel::cross;
  o.shift = TemperatureShift::arrhenius;
  CHECK_THROWS_AS(fit_viscosity(d, o), tunekit::InputError);
  o.shift = TemperatureShift::none;
  CHECK_NOTHROW(fit_viscosity(d, o));
  // Fewer points than parameters.
  RheologyData few = d;
  few.shear_rate_1_s.resize(3);
  few.viscosity_Pa_s.resize(3);
  few.temperature_K.resize(3);
  CHECK_THROWS_AS(fit_viscosity(few, o), tunekit::InputError);
}

TEST_CASE("model comparison prefers Cross over a power law on Cross data, and Carreau-Yasuda recovers its parameters") {
  RheologyData d;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.02);
  for (int i = 0; i < 40; ++i) {
    const double g = std::pow(10.0, -1 + i * 5.0 / 39);
    d.shear_rate_1_s.push_back(g);
    d.temperature_K.push_back(663.15);
    d.viscosity_Pa_s.push_back(cross_viscosity(2500, 1e5, 0.45, g) * std::exp(noise(rng)));
  }
  const auto cmp = compare_viscosity_models(d, default_candidates(d));
  REQUIRE(cmp.entries.size() == 4);
  CHECK((cmp.best == "cross" || cmp.best == "carreau-yasuda"));
  double aic_cross = 0, aic_pl = 0;
  for (const auto& e : cmp.entries) {
    REQUIRE(e.ok);
    if (e.model == "cross") aic_cross = e.aic;
    if (e.model == "power-law") aic_pl = e.aic;
  }
  CHECK(aic_cross < aic_pl - 50);
  const auto j = to_json(cmp);
  CHECK(j["models"].size() == 4);

  RheologyData cy = d;
  for (std::size_t i = 0; i < cy.size(); ++i)
    cy.viscosity_Pa_s[i] =
        carreau_yasuda_viscosity(3000, 0, 0.05, 1.5, 0.4, cy.shear_rate_1_s[i]) * std::exp(noise(rng));
  ViscosityFitOptions o;
  o.model = ViscosityModel::carreau_yasuda;
  const auto fit = fit_viscosity(cy, o);
  check_within_ci(fit, "eta0_Pa_s", 3000);
  check_within_ci(fit, "lambda_s", 0.05);
  check_within_ci(fit, "a", 1.5);
  check_within_ci(fit, "n", 0.4);
}

TEST_CASE("model comparison: equivalent models tie, and the tie goes to the earlier candidate") {
  // Cross with a WLF shift and Cross-WLF (A2 held, no pressure) are the same family: ln eta0(T)
  // = const + B / (c + T) with three free constants each. Their AICs agree to rounding, and the
  // winner must not depend on the last digits.
  RheologyData d;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.03);
  for (double degc : {380.0, 400.0, 420.0})
    for (int i = 0; i < 20; ++i) {
      const double g = std::pow(10.0, i * 4.0 / 19), T = celsius_to_kelvin(degc);
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(cross_wlf_viscosity(peek(), g, T) * std::exp(noise(rng)));
    }
  ViscosityFitOptions shifted, cwlf;
  shifted.model = ViscosityModel::cross;
  shifted.shift = TemperatureShift::wlf;
  cwlf.model = ViscosityModel::cross_wlf;
  const auto ab = compare_viscosity_models(d, {shifted, cwlf});
  REQUIRE(ab.entries.size() == 2);
  REQUIRE(ab.entries[0].ok);
  REQUIRE(ab.entries[1].ok);
  REQUIRE(ab.entries[0].aic == Approx(ab.entries[1].aic).epsilon(1e-9));
  CHECK(ab.best == "cross+wlf");
  CHECK(compare_viscosity_models(d, {cwlf, shifted}).best == "cross-wlf");
}

TEST_CASE("Cross with an Arrhenius shift and time-temperature superposition") {
  RheologyData d;
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0, 0.02);
  const double Ea = 120e3, Tref = 653.15;
  for (double T : {633.15, 653.15, 673.15, 693.15})
    for (int i = 0; i < 15; ++i) {
      const double g = std::pow(10.0, i * 4.0 / 14);
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(cross_viscosity(3000 * arrhenius_shift(T, Ea, Tref), 8e4, 0.4, g) *
                                 std::exp(noise(rng)));
    }
  ViscosityFitOptions o;
  o.model = ViscosityModel::cross;
  o.shift = TemperatureShift::arrhenius;
  o.T_ref_K = Tref;
  const auto fit = fit_viscosity(d, o);
  CHECK(fit.model == "cross+arrhenius");
  check_within_ci(fit, "Ea_J_per_mol", Ea);
  check_within_ci(fit, "eta0_Pa_s", 3000);
  CHECK(fit.value("T_ref_K") == Tref);

  const auto tts = time_temperature_superposition(d, Tref);
  REQUIRE(tts.temperatures_K.size() == 4);
  for (std::size_t k = 0; k < 4; ++k) {
    const double truth = arrhenius_shift(tts.temperatures_K[k], Ea, Tref);
    // Within three standard errors of ln a_T (four shift factors: a 95 % interval alone
    // misses one of them too often for a fixed-seed test).
    const double se = (std::log(tts.shift_factor_hi[k]) - std::log(tts.shift_factor_lo[k])) / (2 * 1.96);
    INFO("T " << tts.temperatures_K[k] << " a_T " << tts.shift_factor[k] << " truth " << truth << " se(ln) " << se);
    CHECK(std::abs(std::log(tts.shift_factor[k]) - std::log(truth)) <= 3 * se + 1e-12);
    if (k > 0) CHECK(se < 0.05);
  }
  REQUIRE(tts.has_arrhenius);
  check_within_ci(tts.arrhenius, "Ea_J_per_mol", Ea);
  CHECK(tts.reduced_shear_rate_1_s.size() == d.size());
  const auto j = to_json(tts);
  CHECK(j["shift_factors"].size() == 4);
}

TEST_CASE("inverse nozzle fit recovers K, n and Ea from Boles pressure drops") {
  NozzleGeometry g;
  NozzleFlowData d;
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0, 0.02);
  const double Tref = 678.15;
  for (double T : {668.15, 678.15, 688.15})
    for (double q : {1.0, 1.5, 3.0, 4.5, 6.0}) {
      d.flow_m3_s.push_back(q * 1e-9);
      d.temperature_K.push_back(T);
      d.pressure_Pa.push_back(boles_dp(7988 * arrhenius_shift(T, 150e3, Tref), 0.539, q * 1e-9, g) *
                              std::exp(noise(rng)));
    }
  const auto fit = fit_nozzle_rheology(d, PressureModel::boles, g);
  check_within_ci(fit, "K_Pa_s_n", 7988);
  check_within_ci(fit, "n", 0.539);
  check_within_ci(fit, "Ea_J_per_mol", 150e3);
}

TEST_CASE("liquefier prediction: shear thinning makes tau fall with flow") {
  const auto spec = ViscositySpec::from_cross_wlf(peek());
  tunekit::ident::LiquefierPredictionOptions o;
  o.temperature_K = celsius_to_kelvin(405);
  const auto p = tunekit::ident::predict_liquefier(spec, o);
  REQUIRE(p.flow_mm3_s.size() == o.flows_mm3_s.size());
  for (std::size_t i = 0; i < p.flow_mm3_s.size(); ++i) {
    if (p.flow_mm3_s[i] == o.reference_flow_mm3_s) CHECK(p.relative_tau[i] == Approx(1.0).epsilon(1e-12));
    if (i > 0) {
      CHECK(p.relative_tau[i] < p.relative_tau[i - 1]);
      CHECK(p.pressure_drop_Pa[i] > p.pressure_drop_Pa[i - 1]);
    }
    CHECK(p.flow_index_n[i] > 0.4);
    CHECK(p.flow_index_n[i] < 1.0);
  }
  // For a pure power law R ~ Q^(n-1): relative tau at 2x the reference flow is 2^(n-1).
  ViscositySpec pl;
  pl.model = ViscosityModel::power_law;
  pl.values = {{"K_Pa_s_n", 8000}, {"n", 0.54}};
  o.flows_mm3_s = {3, 6};
  const auto q = tunekit::ident::predict_liquefier(pl, o);
  CHECK(q.relative_tau[1] == Approx(std::pow(2.0, 0.54 - 1)).epsilon(1e-6));
  const auto j = tunekit::ident::to_json(q);
  for (const char* k : {"temperature_K", "flow_mm3_s", "dP_dQ_Pa_s_per_mm3", "relative_tau", "reference_flow_mm3_s"})
    CHECK(j.contains(k));
}
