// The thermal experiment's safety: no heater-identify G-code commands a temperature above the
// profile's maximum (refused before any G-code, and the gate finds nothing in what is built), it
// takes at most five minutes of machine time, and a run on the simulated printer leaves the heater
// off whether it completes or is stopped by a failure; its record is fitted by `tunekit thermal`.
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/dialect.hpp"
#include "tunekit/history/quantities.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/safety.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using tunekit::test::read_json;
using tunekit::test::read_text;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;

namespace {

/// Every hot-end temperature the G-code sets (M104/M109 S or R), degC.
std::vector<double> hotend_temperatures(const std::vector<std::string>& gcode) {
  std::vector<double> out;
  for (const auto& line : gcode) {
    const auto w = tunekit::machine::parse_gcode(line.substr(0, line.find(';')));
    if (!w || (w->command != "M104" && w->command != "M109")) continue;
    out.push_back(w->has("S") ? w->get("S", 0) : w->get("R", 0));
  }
  return out;
}

}  // namespace

TEST_CASE("heater-identify refuses a printing temperature above the profile's maximum before any G-code",
          "[thermal][safety]") {
  auto profile = tunekit::sim::builtin_sim_profile();
  const tunekit::firmware::Dialect marlin;
  CHECK_THROWS_AS(tunekit::protocols::build_experiment("heater-identify", {{"hotend_c", 281}}, "", profile, marlin),
                  tunekit::InputError);
  profile.temperature.hotend_max_c = 200;  // the default 210 is then above it
  CHECK_THROWS_AS(tunekit::protocols::build_experiment("heater-identify", {}, "", profile, marlin),
                  tunekit::InputError);
  const auto r = run_cli({"run", "heater-identify", "--dry-run", "-p", "hotend_c=300"});
  CHECK(r.code == 2);
  CHECK(r.err.find("hotend_max_c") != std::string::npos);
}

TEST_CASE("property: no heater-identify G-code sets a temperature above the profile's maximum, on any firmware",
          "[thermal][safety]") {
  for (const auto fw : {tunekit::firmware::Firmware::marlin, tunekit::firmware::Firmware::klipper,
                        tunekit::firmware::Firmware::reprapfirmware}) {
    const tunekit::firmware::Dialect d(fw);
    for (double max_c : {150.0, 220.0, 280.0, 350.0}) {
      auto profile = tunekit::sim::builtin_sim_profile();
      profile.temperature.hotend_max_c = max_c;
      for (double hot = max_c - 60; hot <= max_c + 30; hot += 15) {
        INFO("max " << max_c << " hotend_c " << hot);
        if (hot > max_c) {
          CHECK_THROWS_AS(tunekit::protocols::build_experiment("heater-identify", {{"hotend_c", hot}}, "", profile, d),
                          tunekit::InputError);
          continue;
        }
        const auto e = tunekit::protocols::build_experiment("heater-identify", {{"hotend_c", hot}}, "", profile, d);
        for (double t : hotend_temperatures(e.gcode)) CHECK(t <= max_c);
        CHECK(tunekit::protocols::check_protocol(e.gcode, profile, e.sensors).empty());
        CHECK(e.estimated_duration_s <= 300);
        // The last hot-end command turns the heater off.
        REQUIRE_FALSE(hotend_temperatures(e.gcode).empty());
        CHECK(hotend_temperatures(e.gcode).back() == 0);
      }
    }
  }
}

TEST_CASE("heater-identify on the simulator ends with the heater off and its record predicts the held-out steps",
          "[thermal]") {
  const auto dir = scratch_dir("thermal_run") + "/run";
  const auto r = run_cli({"run", "heater-identify", "--machine", "sim", "--run-dir", dir});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto stats = read_json(dir + "/sim_stats.json");
  CHECK(stats["hot_end"]["target_c"] == 0);
  CHECK(stats["hot_end"]["heater_duty"] == 0);
  CHECK(stats["machine_time_s"].get<double>() <= 300);
  const auto f = run_cli({"thermal", dir + "/thermal.csv", "--json"});
  INFO(f.err);
  REQUIRE(f.code == 0);
  const auto res = nlohmann::json::parse(f.out)["results"];
  CHECK(res["held_out"]["rms_c"].get<double>() < 1.0);
  REQUIRE(res["held_out"]["steps"].size() == 2);
  for (const auto& s : res["held_out"]["steps"]) CHECK(s["rms_c"].get<double>() < 1.0);
  // The default simulated hot end's truth within each interval's reach.
  const auto truth = read_json(dir + "/truth.json")["hot_end"];
  for (const char* k : {"block_heat_capacity_j_per_k", "sensor_responsiveness_per_s", "ambient_transfer_w_per_k",
                        "fan_transfer_w_per_k", "filament_heat_capacity_j_per_k_mm"}) {
    const auto& p = res["params"][k];
    const double v = truth[k], half = 0.5 * (p["ci95"][1].get<double>() - p["ci95"][0].get<double>());
    INFO(k << " " << p.dump() << " truth " << v);
    CHECK(std::abs(p["value"].get<double>() - v) < 2 * half);
  }
}

TEST_CASE("a heater-identify run stopped by a machine failure leaves the heater off", "[thermal][safety]") {
  // The 20th line received is in the middle of the experiment, the heater on.
  for (const std::string fault : {"drop@20", "error@20"}) {
    const auto dir = scratch_dir("thermal_stop_" + fault.substr(0, fault.find('@'))) + "/run";
    const auto r = run_cli({"run", "heater-identify", "--machine", "sim", "--run-dir", dir, "--sim", "fault=" + fault,
                            "--timeout", "1", "--retries", "0"});
    INFO(fault << ": " << r.err);
    CHECK(r.code == 3);
    const auto stats = read_json(dir + "/sim_stats.json");
    CHECK(stats["hot_end"]["target_c"] == 0);
    CHECK(stats["hot_end"]["heater_duty"] == 0);
    const std::string rx = read_text(dir + "/sim_received.gcode");
    CHECK(rx.find("M104 S210") != std::string::npos);   // it had heated
    CHECK(rx.rfind("M104 S0") > rx.find("M104 S210"));  // and the host turned it off after
  }
}

TEST_CASE(
    "heater-identify on a Marlin without tunekit's stream records its M155 auto-reports and predicts the held-out "
    "steps",
    "[thermal]") {
  const auto dir = scratch_dir("thermal_m155") + "/run";
  const auto r = run_cli({"run", "heater-identify", "--machine", "sim", "--run-dir", dir, "--sim", "sensor_stream=0"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string rx = read_text(dir + "/sim_received.gcode");
  CHECK(rx.find("M4100") == std::string::npos);
  const auto on = rx.find("M155 S1"), off = rx.find("M155 S0");
  REQUIRE(on != std::string::npos);
  REQUIRE(off != std::string::npos);
  CHECK(on < rx.find("M104 S210"));    // recording from rest, before the heater is on
  CHECK(off > rx.rfind("M104 S210"));  // and to the plan's end
  CHECK(rx.rfind("M104 S0") > off);    // the heater off after
  const auto stats = read_json(dir + "/sim_stats.json");
  CHECK(stats["hot_end"]["target_c"] == 0);
  CHECK(stats["hot_end"]["heater_duty"] == 0);
  // One report a second over the 286 s record.
  CHECK(std::abs(read_json(dir + "/run.json")["samples"]["thermal"].get<double>() - 286) <= 2);
  const auto f = run_cli({"thermal", dir + "/thermal.csv", "--json"});
  INFO(f.err);
  REQUIRE(f.code == 0);
  const auto res = nlohmann::json::parse(f.out)["results"];
  CHECK(res["held_out"]["rms_c"].get<double>() < 1.0);
  REQUIRE(res["held_out"]["steps"].size() == 2);
  for (const auto& s : res["held_out"]["steps"]) CHECK(s["rms_c"].get<double>() < 1.0);
}

TEST_CASE("heater-identify on a Marlin without AUTO_REPORT_TEMPERATURES is refused before homing or heating",
          "[thermal][safety]") {
  const auto dir = scratch_dir("thermal_no_autoreport") + "/run";
  const auto r = run_cli({"run", "heater-identify", "--machine", "sim", "--run-dir", dir, "--sim", "sensor_stream=0",
                          "--sim", "autoreport_temp=0"});
  CHECK(r.code == 3);
  CHECK(r.err.find("AUTO_REPORT_TEMPERATURES") != std::string::npos);
  const std::string rx = read_text(dir + "/sim_received.gcode");
  CHECK(rx.find("G28") == std::string::npos);
  CHECK(rx.find("M104 S2") == std::string::npos);
  CHECK(rx.find("M155") == std::string::npos);
}

TEST_CASE("a heater-identify run on Marlin's auto-reports stopped by a failure turns the reports and the heater off",
          "[thermal][safety]") {
  for (const std::string fault : {"drop@20", "error@20"}) {
    const auto dir = scratch_dir("thermal_m155_stop_" + fault.substr(0, fault.find('@'))) + "/run";
    const auto r = run_cli({"run", "heater-identify", "--machine", "sim", "--run-dir", dir, "--sim", "sensor_stream=0",
                            "--sim", "fault=" + fault, "--timeout", "1", "--retries", "0"});
    INFO(fault << ": " << r.err);
    CHECK(r.code == 3);
    const auto stats = read_json(dir + "/sim_stats.json");
    CHECK(stats["hot_end"]["target_c"] == 0);
    CHECK(stats["hot_end"]["heater_duty"] == 0);
    const std::string rx = read_text(dir + "/sim_received.gcode");
    const auto heated = rx.find("M104 S210");
    REQUIRE(heated != std::string::npos);  // it had heated, reports on
    CHECK(rx.find("M155 S1") < heated);
    CHECK(rx.rfind("M155 S0") > heated);  // the host stopped the reports
    CHECK(rx.rfind("M104 S0") > heated);  // and turned the heater off
  }
}

TEST_CASE("calibrate --thermal identifies the hot end first, reports it and records it for the history",
          "[thermal][calibrate]") {
  const auto dir = scratch_dir("thermal_calibrate") + "/run";
  // The axes as well: calibrate exports compensators, and the thermal model is not one yet.
  const auto r = run_cli({"calibrate", "--machine", "sim", "--thermal", "--skip-liquefier", "--out", dir, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto results = nlohmann::json::parse(r.out)["results"];
  REQUIRE(results.contains("thermal"));
  CHECK(results["thermal"]["held_out"]["rms_c"].get<double>() < 1.0);
  CHECK(read_text(dir + "/report.html").find("Hot end: the heater's duty") != std::string::npos);
  CHECK(read_json(dir + "/plotdata.json").contains("thermal"));
  // The history's quantities: the hot end's parameters, so that their drift shows.
  const auto q = tunekit::history::extract_quantities("calibrate", results);
  bool heat_capacity = false;
  for (const auto& x : q) heat_capacity |= x.name == "hot_end.block_heat_capacity_j_per_k" && x.value > 0;
  CHECK(heat_capacity);
  // The analysis is reproduced by the command its README names.
  CHECK(read_text(dir + "/analysis/README").find("tunekit thermal heater/thermal.csv") != std::string::npos);
}

TEST_CASE("tunekit thermal: a record without a heater duty is bad input, one that cannot be fitted a fit failure",
          "[thermal]") {
  std::string no_duty = "time (s),temperature (degC)\n", flat = "time (s),temperature (degC),heater_duty (1)\n";
  for (int i = 0; i < 40; ++i) {
    no_duty += std::to_string(i) + ",25\n";
    flat += std::to_string(i) + ",25,0\n";
  }
  const auto bad = run_cli({"thermal", tunekit::test::write_scratch("thermal_no_duty.csv", no_duty)});
  CHECK(bad.code == 2);
  CHECK(bad.err.find("heater_duty") != std::string::npos);
  CHECK(bad.out.empty());
  // Nothing happens in the record: the fit is refused (exit 1), no number is printed.
  const auto none = run_cli({"thermal", tunekit::test::write_scratch("thermal_flat.csv", flat), "--json"});
  CHECK(none.code == 1);
  CHECK(none.out.find("block_heat_capacity_j_per_k") == std::string::npos);
}
