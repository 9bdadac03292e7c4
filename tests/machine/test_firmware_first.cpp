// The firmware on the link is identified before the protocol is built: the bundled profile
// (datasets/machines/sim.toml, which names Marlin) run against a Klipper API server gets
// protocols in Klipper's commands, within the stricter of the profile's and Klipper's limits,
// and the sweep keeps its nominal timeline on Klipper's planner rules (the simulator's).
// Klipper's behaviour: O'Connor et al., Klipper 3D printer firmware (v0.13.0-730, 2026):
// gcode.py cmd_default answers a command no module registered with 'Unknown command:"..."'
// and does not run it; toolhead.py SET_VELOCITY_LIMIT sets ACCEL and MINIMUM_CRUISE_RATIO.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "fake_klipper.hpp"
#include "test_support.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/klipper_settings.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using tunekit::test::FakeKlipper;
using tunekit::test::FakeKlipperConfig;
using tunekit::test::scratch_dir;
namespace tprot = tunekit::protocols;

namespace {

tprot::RunOptions bundled_profile_on(const std::string& sock, const std::string& protocol, const std::string& dir) {
  tprot::RunOptions o;
  o.protocol = protocol;
  o.machine = tunekit::test::dataset("machines/sim.toml");
  o.port = "unix:" + sock;
  o.run_dir = dir;
  if (tprot::protocol_spec(protocol).uses_axis) o.axis = "x";
  tunekit::calibration::load_run_machine(o, "", {});
  return o;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + " ";
  return s;
}

}  // namespace

TEST_CASE("every protocol built for the bundled profile uses only commands a Klipper peer knows",
          "[machine][klipper]") {
  for (const auto& spec : tprot::protocol_specs()) {
    INFO("protocol " << spec.name);
    const auto dir = scratch_dir("fw_first_" + spec.name);
    const std::string sock = dir + "/klippy_uds";
    FakeKlipperConfig fake;
    fake.load_cell = "load_cell";
    FakeKlipper server(sock, tunekit::sim::SimConfig::from_options({"firmware=klipper"}), fake);
    auto o = bundled_profile_on(sock, spec.name, dir + "/run");
    if (spec.name == "axis-sweep") o.params = {{"freq_start_hz", 35}, {"freq_end_hz", 70}, {"hz_per_sec", 3}};
    if (spec.name == "heater-identify") {
      // The heater is not recorded over Klipper's API yet: refused after the identification,
      // before the protocol (no heating, no homing; only the failure's safe state follows).
      CHECK_THROWS_AS(tprot::run_experiment(o), tunekit::MachineError);
      for (const auto& script : server.scripts()) {
        INFO(script);
        CHECK(script.find("G28") == std::string::npos);
        CHECK(script.find("M104 S2") == std::string::npos);
        CHECK(script.find("M109") == std::string::npos);
      }
      continue;
    }
    const auto res = tprot::run_experiment(o);
    REQUIRE(res.status == "complete");
    // Identified before anything else was sent: info, then the configuration in force.
    const auto requests = server.requests();
    REQUIRE(requests.size() >= 2);
    CHECK(requests[0]["method"] == "info");
    CHECK(requests[1]["method"] == "objects/query");
    INFO("unknown to Klipper: " << joined(server.unknown_commands()));
    CHECK(server.unknown_commands().empty());
    for (const auto& s : server.scripts()) {
      CHECK(s.find("M201") == std::string::npos);
      CHECK(s.find("M205") == std::string::npos);
    }
    CHECK(res.summary["dialect"] == "klipper");
    // The profile names Marlin: overridden, with a warning that names both.
    REQUIRE(res.summary.contains("warnings"));
    const std::string w = res.summary["warnings"][0];
    CHECK(w.find("'marlin'") != std::string::npos);
    CHECK(w.find("Klipper") != std::string::npos);
  }
}

TEST_CASE("the axis sweep on a Klipper peer takes its nominal time within 2 %", "[machine][klipper]") {
  const auto dir = scratch_dir("fw_first_sweep_time");
  const std::string sock = dir + "/klippy_uds";
  FakeKlipper server(sock, tunekit::sim::SimConfig::from_options({"firmware=klipper"}));
  auto o = bundled_profile_on(sock, "axis-sweep", dir + "/run");
  o.params = {{"freq_start_hz", 20}, {"freq_end_hz", 60}, {"hz_per_sec", 4}};
  const auto res = tprot::run_experiment(o);
  REQUIRE(res.status == "complete");
  // Nominal: the sweep's design, settle + its moves + settle. The moves follow f(t) = f0 + rate t
  // for (f1 - f0) / rate, with Klipper's sweeping motion on (by default on Klipper) adding only
  // the stop at the end and the short holds at the slowest points.
  const auto& p = res.experiment.params;
  CHECK(p.at("sweeping_accel") > 0);
  const double moves_s = res.experiment.excitation["sweep_duration_s"].get<double>();
  CHECK(moves_s == Approx((p.at("freq_end_hz") - p.at("freq_start_hz")) / p.at("hz_per_sec")).epsilon(0.01));
  const double nominal = 2 * p.at("settle_s") + moves_s;
  // On the peer: the span of the samples it streamed while recording.
  std::istringstream in(tunekit::test::read_text(res.files.at(tunekit::protocols::RunFile::accel)));
  std::vector<double> t;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') t.push_back(std::stod(line.substr(0, line.find(','))));
  REQUIRE(t.size() > 100);
  const double on_peer = t.back() - t.front();
  INFO("nominal " << nominal << " s, on the peer " << on_peer << " s");
  CHECK(nominal >= 10);  // 40 Hz at 4 Hz/s plus two settles
  CHECK(std::abs(on_peer / nominal - 1) < 0.02);
  CHECK(server.unknown_commands().empty());
}

TEST_CASE("a profile naming another firmware is refused with both names when asked to be strict",
          "[machine][klipper]") {
  const auto dir = scratch_dir("fw_first_strict");
  const std::string sock = dir + "/klippy_uds";
  FakeKlipper server(sock, tunekit::sim::SimConfig::from_options({"firmware=klipper"}));
  auto o = bundled_profile_on(sock, "axis-rectangle", dir + "/run");
  o.strict_firmware = true;
  try {
    tprot::run_experiment(o);
    FAIL("a Marlin profile ran on Klipper");
  } catch (const tunekit::InputError& e) {
    const std::string m = e.what();
    CHECK(m.find("'marlin'") != std::string::npos);
    CHECK(m.find("Klipper") != std::string::npos);
  }
  // Nothing but the identification reached the machine.
  CHECK(server.scripts().empty());
}

TEST_CASE("Klipper's reported limits are applied where stricter than the profile's", "[machine][klipper]") {
  const auto dir = scratch_dir("fw_first_limits");
  const std::string sock = dir + "/klippy_uds";
  FakeKlipperConfig fake;
  fake.load_cell = "load_cell";
  fake.max_accel = 4200;
  fake.shaper_freq_x = 61.5;
  fake.shaper_freq_y = 47.25;
  // [extruder] max_extrude_only_accel 1200 (the profile allows 5000), max_extrude_only_distance 30.
  const auto sim_cfg = tunekit::sim::SimConfig::from_options(
      {"firmware=klipper", "max_extrude_only_accel_mm_s2=1200", "max_extrude_only_distance_mm=30"});
  auto o = bundled_profile_on(sock, "liquefier-step", dir + "/run");
  {
    // A feed acceleration of 2000 mm/s^2 asked for is within the profile (5000) but not within
    // Klipper's 1200: refused before the protocol's first line is sent.
    o.params = {{"accel_mm_s2", 2000}};
    FakeKlipper refusing(sock, sim_cfg, fake);
    try {
      tprot::run_experiment(o);
      FAIL("a feed acceleration above Klipper's max_extrude_only_accel was sent");
    } catch (const tunekit::InputError& e) {
      CHECK(std::string(e.what()).find("1200") != std::string::npos);
    }
    CHECK(refusing.scripts().empty());
  }
  {
    // The default is derived from the limits in force: Klipper's 1200, reported over the link.
    o.params = {};
    o.run_dir = dir + "/run-default";
    FakeKlipper defaults(sock, sim_cfg, fake);
    const auto res = tprot::run_experiment(o);
    REQUIRE(res.status == "complete");
    CHECK(res.experiment.params.at("accel_mm_s2") == Approx(1200));
  }
  FakeKlipper server(sock, sim_cfg, fake);
  o.params = {{"accel_mm_s2", 1000}};
  o.run_dir = dir + "/run2";
  const auto res = tprot::run_experiment(o);
  REQUIRE(res.status == "complete");
  const auto& ex = res.experiment.excitation;
  CHECK(ex["extrude_only_accel_mm_s2"].get<double>() == Approx(1000));
  CHECK(ex["max_extrude_only_distance_mm"].get<double>() == Approx(30));
  // The acceleration in force is what the test restores.
  CHECK(std::find(res.gcode.begin(), res.gcode.end(), "SET_VELOCITY_LIMIT ACCEL=4200") != res.gcode.end());
  CHECK(server.unknown_commands().empty());

  // The axis sweep turns the shaper Klipper reports off and restores it.
  const auto dir2 = scratch_dir("fw_first_limits_sweep");
  FakeKlipper server2(dir2 + "/klippy_uds", tunekit::sim::SimConfig::from_options({"firmware=klipper"}), fake);
  auto o2 = bundled_profile_on(dir2 + "/klippy_uds", "axis-sweep", dir2 + "/run");
  o2.params = {{"freq_start_hz", 35}, {"freq_end_hz", 45}, {"hz_per_sec", 5}};
  const auto res2 = tprot::run_experiment(o2);
  const std::string g = [&] {
    std::string s;
    for (const auto& l : res2.gcode) s += l + "\n";
    return s;
  }();
  CHECK(g.find("SET_INPUT_SHAPER SHAPER_FREQ_X=0 SHAPER_FREQ_Y=0") != std::string::npos);
  CHECK(g.find("SHAPER_TYPE_X=mzv SHAPER_FREQ_X=61.5 DAMPING_RATIO_X=0.1") != std::string::npos);
  CHECK(g.find("SHAPER_FREQ_Y=47.25") != std::string::npos);
}

TEST_CASE("Klipper settings: live values win over the configuration, missing ones stay unknown", "[machine][klipper]") {
  const nlohmann::json info{{"state", "ready"}, {"software_version", "v0.13.0-730"}};
  const nlohmann::json query{{"status",
                              {{"configfile",
                                {{"settings",
                                  {{"printer", {{"max_accel", 3000}, {"minimum_cruise_ratio", 0.5}}},
                                   {"extruder", {{"max_extrude_only_accel", 800.0}, {"pressure_advance", 0.05}}},
                                   {"input_shaper", {{"shaper_type_x", "ei"}, {"shaper_freq_x", 55.0}}}}}}},
                               {"toolhead", {{"max_accel", 7000}}},
                               {"extruder", {{"pressure_advance", 0.031}}}}}};
  const auto k = tunekit::machine::parse_klipper_settings(info, query);
  CHECK(k.software_version == "v0.13.0-730");
  CHECK(k.max_accel_mm_s2 == 7000);              // SET_VELOCITY_LIMIT after start-up
  CHECK(k.minimum_cruise_ratio == 0.5);          // from the configuration
  CHECK(k.pressure_advance_s == Approx(0.031));  // SET_PRESSURE_ADVANCE after start-up
  CHECK(std::isnan(k.max_extrude_only_velocity_mm_s));
  REQUIRE(k.shaper.count("x") == 1);
  CHECK(k.shaper.at("x") == "ei:55:0.1");
  CHECK(k.shaper.count("y") == 0);
  std::vector<std::string> notes;
  auto profile = tunekit::sim::builtin_sim_profile();
  const double feed_limit = profile.extruder.max_velocity_mm_s;
  const auto p = tunekit::machine::with_klipper_settings(profile, k, notes);
  CHECK(p.extruder.max_accel_mm_s2 == 800);           // stricter than the profile's 5000
  CHECK(p.extruder.max_velocity_mm_s == feed_limit);  // not reported: the profile's
  CHECK(p.state.accel_in_force_mm_s2 == 7000);
  CHECK(!notes.empty());
}
