// The viscosity fits compute their residuals from the models in logarithms with an analytic
// Jacobian: the residual sum of squares must be that of the public viscosity functions, and the
// standard errors those of a Jacobian of the public functions by central differences.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "test_support.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/fitting/viscosity.hpp"

using namespace tunekit::fitting;

namespace {

// Parameters the fits estimate as logarithms (rheology_fit.hpp: the scale parameters).
const std::set<std::string> kLogParams = {"eta0_Pa_s", "K_Pa_s_n", "tau_star_Pa", "lambda_s", "D1_Pa_s"};

// `truth` at four temperatures over four decades of shear rate, times exp(2 % noise).
RheologyData data_from(const ViscositySpec& truth, unsigned seed) {
  RheologyData d;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.02);
  for (double T : {633.15, 653.15, 673.15, 693.15})
    for (int i = 0; i < 25; ++i) {
      const double g = std::pow(10.0, -1 + i * 4.0 / 24);
      d.shear_rate_1_s.push_back(g);
      d.temperature_K.push_back(T);
      d.viscosity_Pa_s.push_back(truth.viscosity(g, T) * std::exp(noise(rng)));
    }
  return d;
}

// Residuals ln eta(fit) - ln eta_observed through the public ViscositySpec.
std::vector<double> public_residuals(const ViscositySpec& s, const RheologyData& d) {
  std::vector<double> r;
  for (std::size_t i = 0; i < d.size(); ++i)
    r.push_back(std::log(s.viscosity(d.shear_rate_1_s[i], d.temperature_K[i])) - std::log(d.viscosity_Pa_s[i]));
  return r;
}

void check_against_public_model(const RheologyData& d, ViscosityFitOptions o) {
  o.profile_intervals = false;
  const auto fit = fit_viscosity(d, o);
  INFO(fit.model);
  const auto spec = spec_from_fit(fit);
  double rss = 0;
  for (double v : public_residuals(spec, d)) rss += v * v;
  CHECK(fit.diagnostics.rss == Approx(rss).epsilon(1e-9));
  std::vector<std::vector<double>> cols;
  std::vector<const Param*> free;
  for (const auto& p : fit.params) {
    if (p.fixed) continue;
    free.push_back(&p);
    const bool lg = kLogParams.count(p.name) > 0;
    const double u = lg ? std::log(p.value) : p.value, h = 1e-6 * std::max(1.0, std::abs(u));
    auto up = spec, down = spec;
    up.values[p.name] = lg ? std::exp(u + h) : u + h;
    down.values[p.name] = lg ? std::exp(u - h) : u - h;
    const auto ru = public_residuals(up, d), rd = public_residuals(down, d);
    cols.emplace_back();
    for (std::size_t i = 0; i < ru.size(); ++i) cols.back().push_back((ru[i] - rd[i]) / (2 * h));
  }
  const auto diag = tunekit::test::inverse_normal_diagonal(cols);
  const double s2 = fit.diagnostics.rss / static_cast<double>(d.size() - free.size());
  for (std::size_t j = 0; j < free.size(); ++j) {
    INFO(free[j]->name);
    const double se = std::sqrt(s2 * diag[j]) * (kLogParams.count(free[j]->name) ? free[j]->value : 1.0);
    CHECK(free[j]->std_error == Approx(se).epsilon(1e-5));
  }
}

}  // namespace

TEST_CASE("viscosity fits: residuals and standard errors agree with the public models differentiated numerically") {
  ViscositySpec cross;
  cross.model = ViscosityModel::cross;
  cross.shift = TemperatureShift::arrhenius;
  cross.values = {{"eta0_Pa_s", 3000}, {"tau_star_Pa", 8e4}, {"n", 0.4}, {"Ea_J_per_mol", 90e3}, {"T_ref_K", 653.15}};
  const auto cross_data = data_from(cross, 5);
  ViscositySpec cy;
  cy.model = ViscosityModel::carreau_yasuda;
  cy.shift = TemperatureShift::arrhenius;
  cy.values = {{"eta0_Pa_s", 3000}, {"eta_inf_Pa_s", 40},   {"lambda_s", 0.05}, {"a", 1.5},
               {"n", 0.35},         {"Ea_J_per_mol", 90e3}, {"T_ref_K", 653.15}};
  const auto cy_data = data_from(cy, 6);
  const auto cwlf_data = data_from(ViscositySpec::from_cross_wlf(cross_wlf_material("PEEK").params), 7);

  ViscosityFitOptions o;
  o.shift = TemperatureShift::arrhenius;
  for (auto m : {ViscosityModel::newtonian, ViscosityModel::power_law, ViscosityModel::cross}) {
    o.model = m;
    check_against_public_model(cross_data, o);
  }
  o.model = ViscosityModel::cross;
  o.shift = TemperatureShift::wlf;
  check_against_public_model(cross_data, o);
  o.model = ViscosityModel::carreau_yasuda;
  o.shift = TemperatureShift::arrhenius;
  o.free = {"eta_inf_Pa_s"};
  check_against_public_model(cy_data, o);
  o = {};
  o.model = ViscosityModel::cross_wlf;
  check_against_public_model(cwlf_data, o);
}
