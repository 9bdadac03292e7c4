// A klippy.log read and fitted: the heater's Stats lines, written as Klipper writes them
// (klippy/extras/heaters.py Heater.stats: "extruder: target=%.0f temp=%.1f pwm=%.3f", once a
// second, statistics.py "Stats %.1f:"), read into a thermal record and fitted by the thermal fit;
// the residuals are those of the temperature Klipper printed (0.1 degC steps) against the model.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/formats/heater_log.hpp"
#include "tunekit/ident/heater_log_record.hpp"
#include "tunekit/ident/thermal_fit.hpp"

using namespace tunekit;

// The file's helpers in a namespace of their own: the test areas are unity builds.
namespace test_heater_log_fit {

ident::ThermalModel truth() {
  ident::ThermalModel m;
  m.heater_power_w = 40.0;
  m.block_heat_capacity_j_per_k = 13.0;
  m.sensor_responsiveness_per_s = 0.17;
  m.ambient_transfer_w_per_k = 0.12;
  m.fan_transfer_w_per_k = 0.12;
  m.ambient_c = 24.0;
  return m;
}

/// A heat-up to 205 degC at full power, then a PI loop holding it (the duty as Klipper would set
/// it), as a klippy.log: the temperature and duty at Klipper's printed precision.
std::string heat_up_log(const ident::ThermalModel& m) {
  ident::ThermalRecord rec;
  for (int i = 0; i < 240; ++i) {
    rec.t_s.push_back(i);
    rec.heater_duty.push_back(0.0);
  }
  // Close the loop sample by sample on the model's own simulation.
  double integ = 0;
  for (int i = 0; i < 240; ++i) {
    ident::ThermalRecord head = rec;
    head.t_s.resize(static_cast<std::size_t>(i) + 1);
    head.heater_duty.resize(static_cast<std::size_t>(i) + 1);
    const double temp = ident::simulate_thermal_record(m, m.ambient_c, head).back();
    const double err = 205.0 - temp;
    integ = std::clamp(integ + err, 0.0, 100.0);
    rec.heater_duty[static_cast<std::size_t>(i)] = std::clamp(0.1 * err + 0.004 * integ, 0.0, 1.0);
  }
  const auto temps = ident::simulate_thermal_record(m, m.ambient_c, rec);
  std::string log = "Start printer at Sat Dec  7 09:00:00 2024 (1733562000.0 12.0)\n";
  for (std::size_t i = 0; i < rec.t_s.size(); ++i)
    log += fmt::format(
        "Stats {:.1f}: gcodein=0  mcu: mcu_awake=0.005 freq=72000317  heater_bed: target=0 temp=24.0 "
        "pwm=0.000 sysload=0.00 print_stall=0 extruder: target=205 temp={:.1f} pwm={:.3f}\n",
        1000.5 + rec.t_s[i], temps[i], rec.heater_duty[i]);
  return log;
}

}  // namespace test_heater_log_fit

using namespace test_heater_log_fit;

TEST_CASE("A klippy.log heat-up is read and fitted: residuals at the log's precision") {
  const auto m = truth();
  const auto log = formats::read_klippy_heater_log(heat_up_log(m));
  const auto rec = ident::thermal_record_from_heater_log(log, ident::heated_run(log));
  REQUIRE(rec.t_s.size() == 240);
  ident::ThermalFitOptions o;
  o.heater_power_w = m.heater_power_w;
  const auto fit = ident::fit_thermal_record(rec, o);
  double ss = 0;
  for (std::size_t i = 0; i < rec.t_s.size(); ++i) ss += std::pow(rec.temp_c[i] - fit.predicted_c[i], 2);
  const double rms = std::sqrt(ss / static_cast<double>(rec.t_s.size()));
  INFO("residual RMS " << rms << " degC");
  CHECK(rms < 0.1);  // the log rounds to 0.1 degC (and the duty to 0.001): nothing else is left
  CHECK(fit.model.block_heat_capacity_j_per_k == Approx(m.block_heat_capacity_j_per_k).epsilon(0.05));
  CHECK(fit.model.sensor_responsiveness_per_s == Approx(m.sensor_responsiveness_per_s).epsilon(0.1));
  CHECK(fit.model.ambient_transfer_w_per_k == Approx(m.ambient_transfer_w_per_k).epsilon(0.1));
}

TEST_CASE("The real klippy.log heat-up (datasets/thermal/klippy_cetus3d) is fitted, its residuals shown") {
  // The heat-up at max_power 0.7 from 16 degC and the first minutes held at 230 degC: the first
  // 300 s of the excerpt. The heater's power is not in the log: 40 W is assumed (a common
  // cartridge); C and A scale with it, R and the temperatures do not.
  const auto h = formats::read_klippy_heater_log(
      tunekit::test::read_text(tunekit::test::dataset("thermal/klippy_cetus3d/klippy-heatup.log")));
  auto rec = ident::thermal_record_from_heater_log(h, ident::heated_run(h));
  std::size_t n = 0;
  while (n < rec.t_s.size() && rec.t_s[n] <= 300.0) ++n;
  for (auto* v : {&rec.t_s, &rec.temp_c, &rec.heater_duty, &rec.target_c}) v->resize(n);
  ident::ThermalFitOptions o;
  o.heater_power_w = 40.0;
  const auto fit = ident::fit_thermal_record(rec, o);
  double ss = 0, worst = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rec.temp_c[i] - fit.predicted_c[i];
    ss += r * r;
    worst = std::max(worst, std::abs(r));
  }
  const double rms = std::sqrt(ss / static_cast<double>(n));
  WARN("real heat-up: C " << fit.model.block_heat_capacity_j_per_k << " J/K, R "
                          << fit.model.sensor_responsiveness_per_s << " 1/s, A " << fit.model.ambient_transfer_w_per_k
                          << " W/K; residual RMS " << rms << " degC, largest " << worst << " degC, variance factor "
                          << fit.variance_factor);
  // The largest residuals are the thermistor's noise at room temperature (readings of 9.5 and
  // 22 degC a few seconds apart before the heater starts); over the heat-up and the hold the
  // model follows within a few degrees.
  CHECK(rms < 2.5);
  CHECK(fit.model.sensor_responsiveness_per_s > 0.03);
  CHECK(fit.model.sensor_responsiveness_per_s < 0.3);
  CHECK(fit.model.block_heat_capacity_j_per_k > 3.0);
  CHECK(fit.model.block_heat_capacity_j_per_k < 20.0);
}

TEST_CASE("tunekit thermal reads a klippy.log as it is and shows the real heat-up's fit and residuals") {
  const auto log = tunekit::test::dataset("thermal/klippy_cetus3d/klippy-heatup.log");
  const auto r = tunekit::test::run_cli({"thermal", log, "--until", "300", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["options"]["format"] == "klippy.log");
  CHECK(j["options"]["heater"] == "extruder");
  const auto& res = j["results"];
  CHECK(res["diagnostics"]["rms"].get<double>() < 2.5);
  CHECK(res["thermal_model"]["sensor_responsiveness_per_s"].get<double>() > 0.03);
  const auto text = tunekit::test::run_cli({"thermal", log, "--until", "300"});
  REQUIRE(text.code == 0);
  CHECK(text.out.find("residuals: rms") != std::string::npos);
  const auto missing = tunekit::test::run_cli({"thermal", log, "--heater", "heater_bed_2"});
  CHECK(missing.code == 2);
}
