// The hot end's thermal model identified from the designed five-minute experiment on the
// simulated hot end: intervals that cover the truth at their rate over drawn plants, the held-out
// fan and extrusion steps predicted, a fit that cannot converge refused.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "tunekit/core/error.hpp"
#include "tunekit/ident/thermal_fit.hpp"
#include "tunekit/protocols/thermal_plan.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/thermal_plant.hpp"

namespace {

using tunekit::ident::ThermalFit;
using tunekit::ident::ThermalRecord;

tunekit::protocols::ThermalPlan default_plan() {
  const std::map<std::string, double> params{
      {"hotend_c", 210}, {"step_down_c", 15}, {"fan_duty", 1}, {"feed_mm_s", std::nan("")}};
  return tunekit::protocols::plan_thermal_experiment(params, tunekit::sim::builtin_sim_profile());
}

/// The plan run on a simulated hot end: the record its heater loop samples.
ThermalRecord run_plan(const tunekit::protocols::ThermalPlan& plan, const tunekit::sim::ThermalPlantTruth& truth,
                       unsigned noise_seed) {
  std::vector<tunekit::sim::ThermalSetting> schedule;
  for (const auto& p : plan.pieces) schedule.push_back({p.from_s, p.target_c, p.fan_duty, p.feed_mm_s});
  return tunekit::sim::run_thermal_schedule(truth, schedule, plan.duration_s, noise_seed);
}

ThermalFit fit_plan(const tunekit::protocols::ThermalPlan& plan, const tunekit::sim::ThermalPlantTruth& truth,
                    unsigned seed) {
  tunekit::ident::ThermalFitOptions o;
  o.heater_power_w = truth.model.heater_power_w;
  o.held_out_from_s = plan.held_out_from_s;
  return tunekit::ident::fit_thermal_record(run_plan(plan, truth, seed), o);
}

std::map<std::string, double> truth_values(const tunekit::sim::ThermalPlantTruth& t) {
  return {{"block_heat_capacity_j_per_k", t.model.block_heat_capacity_j_per_k},
          {"sensor_responsiveness_per_s", t.model.sensor_responsiveness_per_s},
          {"ambient_transfer_w_per_k", t.model.ambient_transfer_w_per_k},
          {"fan_transfer_w_per_k", t.model.fan_transfer_w_per_k},
          {"filament_heat_capacity_j_per_k_mm", t.model.filament_heat_capacity_j_per_k_mm},
          {"ambient_c", t.model.ambient_c},
          {"start_c", t.model.ambient_c}};
}

}  // namespace

TEST_CASE("the designed thermal experiment lasts at most five minutes and stays below the maximum temperature",
          "[thermal]") {
  const auto plan = default_plan();
  CHECK(plan.duration_s <= 300);
  for (const auto& p : plan.pieces) CHECK(p.target_c <= tunekit::sim::builtin_sim_profile().temperature.hotend_max_c);
  CHECK(plan.held_out_from_s < plan.duration_s);
}

TEST_CASE("the thermal fit recovers the default simulated hot end and predicts the held-out steps within 1 degC",
          "[thermal]") {
  const tunekit::sim::ThermalPlantTruth truth;  // the default hot end, its fan loss bent (gamma 1 here)
  const auto plan = default_plan();
  const ThermalFit f = fit_plan(plan, truth, 1);
  INFO("rms " << f.fit.diagnostics.rms << " vif " << f.variance_factor << " held out " << f.held_out_rms_c);
  for (const auto& [name, v] : truth_values(truth)) {
    const auto& p = f.fit.param(name);
    INFO(name << " " << p.value << " [" << p.ci95_lo << ", " << p.ci95_hi << "] truth " << v);
    CHECK(std::abs(p.value - v) < 0.1 * std::abs(v) + 0.5 * (p.ci95_hi - p.ci95_lo) + 1e-9);
  }
  REQUIRE(f.held_out_steps.size() == 2);
  CHECK(f.held_out_steps[0].input == "fan");
  CHECK(f.held_out_steps[1].input == "feed");
  for (const auto& s : f.held_out_steps) CHECK(s.rms_c < 1.0);
  CHECK(f.held_out_rms_c < 1.0);
}

TEST_CASE("on drawn hot ends the held-out fan and extrusion steps are predicted within 1 degC RMS", "[thermal]") {
  const auto plan = default_plan();
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const auto truth = tunekit::sim::draw_thermal_plant(seed);
    const ThermalFit f = fit_plan(plan, truth, seed);
    INFO("seed " << seed);
    REQUIRE(f.held_out_steps.size() == 2);
    for (const auto& s : f.held_out_steps) CHECK(s.rms_c < 1.0);
  }
}

TEST_CASE("a thermal record that cannot be fitted is an error, never a number", "[thermal]") {
  ThermalRecord r;
  for (int i = 0; i < 40; ++i) {
    r.t_s.push_back(i);
    r.temp_c.push_back(25);
    r.heater_duty.push_back(0);
  }
  // Nothing happens: the heat capacity and the sensor's lag are not identifiable.
  CHECK_THROWS_AS(tunekit::ident::fit_thermal_record(r), tunekit::FitError);
  r.heater_duty[3] = 1.5;
  CHECK_THROWS_AS(tunekit::ident::fit_thermal_record(r), tunekit::InputError);
}

TEST_CASE("coverage: every thermal parameter's 95 % interval holds the truth on 90-98 % of 200 drawn hot ends",
          "[thermal][repeats]") {
  const auto plan = default_plan();
  std::map<std::string, int> covered;
  constexpr unsigned kSeeds = 200;
  for (unsigned seed = 1; seed <= kSeeds; ++seed) {
    const auto truth = tunekit::sim::draw_thermal_plant(seed);
    const ThermalFit f = fit_plan(plan, truth, seed);
    for (const auto& [name, v] : truth_values(truth)) {
      const auto& p = f.fit.param(name);
      covered[name] += p.ci95_lo <= v && v <= p.ci95_hi;
    }
  }
  for (const auto& [name, n] : covered) {
    INFO(name << ": " << n << " of " << kSeeds);
    CHECK(n >= 180);
    CHECK(n <= 196);
  }
}
