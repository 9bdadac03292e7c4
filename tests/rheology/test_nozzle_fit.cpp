// The inverse nozzle fit's model: every pressure-drop model scales as K Q^n (the fit's residuals
// rely on it), its standard errors against a finite-difference Jacobian of pressure_drop, and the
// Newtonian (Hagen-Poiseuille) fit with an Arrhenius shift.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/viscosity.hpp"

using namespace tunekit::fitting;

namespace {

constexpr PressureModel kModels[] = {PressureModel::hagen_poiseuille, PressureModel::power_law_capillary,
                                     PressureModel::bellini, PressureModel::boles};

// Measurements of `model` with consistency K (mu for Hagen-Poiseuille), index n and an Arrhenius
// shift at three temperatures, multiplied by exp(2 % noise).
NozzleFlowData nozzle_data(PressureModel model, double K, double n, double Ea, const NozzleGeometry& g) {
  NozzleFlowData d;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.02);
  for (double T : {668.15, 678.15, 688.15})
    for (double q : {0.5, 1.0, 2.0, 3.0, 4.5, 6.0, 9.0, 12.0}) {
      d.flow_m3_s.push_back(q * 1e-9);
      d.temperature_K.push_back(T);
      d.pressure_Pa.push_back(pressure_drop(model, K * arrhenius_shift(T, Ea, 678.15), n, q * 1e-9, g) *
                              std::exp(noise(rng)));
    }
  return d;
}

}  // namespace

TEST_CASE("nozzle pressure drop: every model scales as K Q^n") {
  const NozzleGeometry g;
  for (auto model : kModels)
    for (double n : {0.05, 0.3, 0.7, 1.0}) {
      const double nn = model == PressureModel::hagen_poiseuille ? 1.0 : n;
      for (double q : {0.1, 3.0, 40.0}) {
        INFO(to_string(model) << " n " << nn << " Q " << q << " mm3/s");
        const double unit = pressure_drop(model, 1.0, nn, 1e-9, g);
        CHECK(pressure_drop(model, 2.5e4, nn, q * 1e-9, g) == Approx(2.5e4 * std::pow(q, nn) * unit).epsilon(1e-12));
      }
    }
}

TEST_CASE("nozzle fit: standard errors agree with a finite-difference Jacobian of ln pressure_drop") {
  const NozzleGeometry g;
  for (auto model : {PressureModel::boles, PressureModel::bellini}) {
    INFO(to_string(model));
    const auto d = nozzle_data(model, 8000, 0.45, 90e3, g);
    const auto fit = fit_nozzle_rheology(d, model, g);
    const double lnK = std::log(fit.value("K_Pa_s_n")), n = fit.value("n"), Ea = fit.value("Ea_J_per_mol");
    const double T_ref = fit.value("T_ref_K");
    auto ln_dp = [&](std::size_t i, double a, double b, double c) {
      return std::log(
          pressure_drop(model, std::exp(a) * arrhenius_shift(d.temperature_K[i], c, T_ref), b, d.flow_m3_s[i], g));
    };
    std::vector<std::vector<double>> cols(3);
    const double h[3] = {1e-5, 1e-6, 1e-1};
    for (std::size_t i = 0; i < d.flow_m3_s.size(); ++i) {
      cols[0].push_back((ln_dp(i, lnK + h[0], n, Ea) - ln_dp(i, lnK - h[0], n, Ea)) / (2 * h[0]));
      cols[1].push_back((ln_dp(i, lnK, n + h[1], Ea) - ln_dp(i, lnK, n - h[1], Ea)) / (2 * h[1]));
      cols[2].push_back((ln_dp(i, lnK, n, Ea + h[2]) - ln_dp(i, lnK, n, Ea - h[2])) / (2 * h[2]));
    }
    const auto diag = tunekit::test::inverse_normal_diagonal(cols);
    const double s2 = fit.diagnostics.rss / static_cast<double>(d.flow_m3_s.size() - 3);
    // K is estimated as ln K: its standard error is K times that of ln K.
    CHECK(fit.param("K_Pa_s_n").std_error == Approx(fit.value("K_Pa_s_n") * std::sqrt(s2 * diag[0])).epsilon(1e-5));
    CHECK(fit.param("n").std_error == Approx(std::sqrt(s2 * diag[1])).epsilon(1e-5));
    CHECK(fit.param("Ea_J_per_mol").std_error == Approx(std::sqrt(s2 * diag[2])).epsilon(1e-5));
  }
}

TEST_CASE("nozzle fit: Hagen-Poiseuille with an Arrhenius shift recovers mu and Ea") {
  const NozzleGeometry g;
  const auto d = nozzle_data(PressureModel::hagen_poiseuille, 600, 1.0, 120e3, g);
  const auto fit = fit_nozzle_rheology(d, PressureModel::hagen_poiseuille, g);
  REQUIRE(fit.params.size() == 3);  // mu, Ea, T_ref (held)
  CHECK(fit.value("mu_Pa_s") == Approx(600).epsilon(0.02));
  CHECK(fit.value("Ea_J_per_mol") == Approx(120e3).epsilon(0.05));
  CHECK(fit.value("T_ref_K") == Approx(678.15));
  CHECK(fit.diagnostics.rms < 0.03);
}
