// Klipper's sensor streams: every accelerometer chip Klipper reads, its load cell, and the
// extruder's trapq that puts the commanded feed on the load cell's print-time clock. The server
// is fake_klipper.hpp, whose message shapes come from Klipper's source (see its header).
#include <filesystem>
#include <fstream>
#include <algorithm>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "fake_klipper.hpp"
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/klipper_sensors.hpp"
#include "tunekit/machine/machine_profile.hpp"

using tunekit::test::FakeKlipper;
using tunekit::test::FakeKlipperConfig;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;
namespace fs = std::filesystem;
namespace tp = tunekit::machine;

namespace {

// The simulated printer's profile with its [sensors] section replaced.
std::string klipper_profile(const std::string& dir, const std::string& sensors, bool klipper_planner = true) {
  std::string text = tunekit::test::read_text(tunekit::test::dataset("machines/sim.toml"));
  // A Klipper printer: the protocols are built for Klipper's planner; the simulated machine's
  // [firmware_state] is kept.
  const auto fw = text.find("firmware = \"marlin\"");
  if (klipper_planner && fw != std::string::npos)
    text.replace(fw, std::string("firmware = \"marlin\"").size(), "firmware = \"klipper\"");
  const auto state = text.find("[firmware_state]");
  text = text.substr(0, text.find("[sensors]")) + "[sensors]\n" + sensors + "\n" +
         (state == std::string::npos ? std::string() : text.substr(state));
  const std::string path = dir + "/printer.toml";
  std::ofstream(path) << text;
  return path;
}

std::size_t klipper_csv_rows(const std::string& path) {
  std::ifstream f(path);
  std::string line;
  std::size_t n = 0;
  while (std::getline(f, line))
    if (!line.empty() && line[0] != '#' && line[0] != 't') ++n;
  return n;
}

}  // namespace

TEST_CASE("Klipper sensor endpoints: chip, section and mux key as Klipper registers them", "[machine]") {
  // adxl345.py:228-231 and the others: "<module>/dump_<module>", key "sensor", the section's last word.
  auto e = tp::klipper_accelerometer_endpoint("lis2dw", "lis2dw toolhead");
  CHECK(e.method == "lis2dw/dump_lis2dw");
  CHECK(e.key == "sensor");
  CHECK(e.value == "toolhead");
  CHECK(tp::klipper_accelerometer_endpoint("lis3dh", "lis3dh").method == "lis2dw/dump_lis2dw");  // lis3dh.py
  CHECK(tp::klipper_accelerometer_endpoint("mpu6050", "mpu9250").method == "mpu9250/dump_mpu9250");
  CHECK(tp::klipper_accelerometer_endpoint("icm20948", "").value == "icm20948");
  CHECK(tp::klipper_accelerometer_endpoint("adxl345", "adxl345").params({{"k", 1}}) ==
        nlohmann::json{{"sensor", "adxl345"}, {"response_template", {{"k", 1}}}});
  CHECK_THROWS_AS(tp::klipper_accelerometer_endpoint("bma400", ""), tunekit::InputError);
  // load_cell.py:394 registers the mux key "load_cell".
  const auto lc = tp::klipper_load_cell_endpoint("load_cell extruder");
  CHECK(lc.method == "load_cell/dump_force");
  CHECK(lc.key == "load_cell");
  CHECK(lc.value == "extruder");
}

TEST_CASE("Klipper sensor rows: grams to newtons, an uncalibrated cell refused, the trapq's feed", "[machine]") {
  // docs/API_Server.md, load_cell/dump_force: {"params":{"data":[[3292.432935, 40.65, 562534, -234467]]}}
  const auto s = tp::parse_load_cell_rows(nlohmann::json::parse(R"({"data":[[3292.432935, 40.65, 562534, -234467]]})"),
                                          "load_cell");
  REQUIRE(s.size() == 1);
  CHECK(s[0].time_s == Approx(3292.432935));
  CHECK(s[0].force_N == Approx(40.65 * 9.80665e-3));
  CHECK_THROWS_AS(tp::parse_load_cell_rows(nlohmann::json::parse(R"({"data":[[1.0, null, 5, 3]]})"), "load_cell"),
                  tunekit::MachineError);
  // docs/API_Server.md, motion_report/dump_trapq's example rows.
  tp::TrapqTimeline tq;
  tq.add(nlohmann::json::parse(
      R"({"data": [[4.05, 1.0, 0.0, 0.0, [300.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [5.054, 0.001, 0.0, 3000.0, [300.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]]})"));
  CHECK(tq.size() == 2);
  CHECK(tq.velocity_x_at(4.5) == 0);
  CHECK(tq.velocity_x_at(5.0545) == Approx(-1.5));  // 3000 mm/s^2 for 0.5 ms along -x
  CHECK(tq.velocity_x_at(6.0) == 0);
  // An extruder entry: signed velocity, direction (1, pressure-advance flag, 0) (kinematics/extruder.py).
  tp::TrapqTimeline ex;
  ex.add(nlohmann::json::parse(R"({"data": [[10.0, 2.0, 3.0, 0.0, [12.5, 0.0, 0.0], [1.0, 1.0, 0.0]]]})"));
  CHECK(ex.velocity_x_at(11.0) == Approx(3.0));
}

TEST_CASE("the trapq's mean feed over a sample's window counts a stop between moves for its share", "[machine]") {
  // Two extrude-only moves that each stop (Klipper does not join them): 3 mm/s cruise, 1 ms ramps
  // at 3000 mm/s^2, a stop at 20 ms. At the stop the speed is 0; over the 5 ms window centred on
  // it the filament moves 2 x (1.5 mm/s x 1 ms + 3 mm/s x 1.5 ms) = 12 um: 2.4 mm/s.
  tp::TrapqTimeline ex;
  ex.add(nlohmann::json::parse(R"({"data": [
      [0.000, 0.001, 0.0, 3000.0, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
      [0.001, 0.018, 3.0, 0.0, [0.0015, 0.0, 0.0], [1.0, 0.0, 0.0]],
      [0.019, 0.001, 3.0, -3000.0, [0.0555, 0.0, 0.0], [1.0, 0.0, 0.0]],
      [0.020, 0.001, 0.0, 3000.0, [0.057, 0.0, 0.0], [1.0, 0.0, 0.0]],
      [0.021, 0.018, 3.0, 0.0, [0.0585, 0.0, 0.0], [1.0, 0.0, 0.0]]]})"));
  CHECK(ex.velocity_x_at(0.020) == Approx(0.0).margin(1e-9));
  CHECK(ex.mean_velocity_x(0.0175, 0.0225) == Approx(2.4));
  CHECK(ex.mean_velocity_x(0.005, 0.010) == Approx(3.0));  // within a cruise
  CHECK(ex.mean_velocity_x(0.030, 0.030) == Approx(3.0));  // an empty window: the speed there
  CHECK(ex.mean_velocity_x(0.050, 0.060) == Approx(0.0));  // after the last move
}

TEST_CASE("an axis sweep recorded under each Klipper accelerometer chip gives the mode within 1 %", "[machine]") {
  struct Chip {
    const char* chip;
    const char* section;
    double f_mode;
  };
  // The same mode under every chip (52.5 Hz, damping 0.06, as the adxl345 test of
  // test_machine_run.cpp): what differs is only the endpoint and object name the data come from.
  const auto c =
      GENERATE(Chip{"adxl345", "adxl345", 52.5}, Chip{"lis2dw", "lis2dw toolhead", 52.5},
               Chip{"lis3dh", "lis3dh", 52.5}, Chip{"mpu9250", "mpu9250 bed", 52.5}, Chip{"mpu6050", "mpu9250", 52.5},
               Chip{"icm20948", "icm20948 hotend", 52.5}, Chip{"bmi160", "bmi160 toolhead", 52.5});
  INFO(c.chip << " [" << c.section << "]");
  const auto dir = scratch_dir(std::string("klipper_chip_") + c.chip);
  const std::string sock = dir + "/klippy_uds";
  FakeKlipperConfig fake;
  fake.accelerometers = {c.section};
  FakeKlipper server(
      sock, tunekit::sim::SimConfig::from_options({"mode_x=" + std::to_string(c.f_mode) + ":0.06", "firmware=klipper"}),
      fake);
  const auto profile = klipper_profile(
      dir, fmt::format("accelerometer = \"{}\"\naccelerometer_name = \"{}\"\nload_cell = false\n", c.chip, c.section));
  const auto r =
      run_cli({"run", "axis-sweep", "--axis", "x", "--machine", profile, "--port", "unix:" + sock, "--run-dir",
               dir + "/run", "-p", "freq_start_hz=35", "-p", "freq_end_hz=70", "-p", "hz_per_sec=3", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  // The subscription went to the chip's own endpoint with the section's object name.
  const auto ep = tp::klipper_accelerometer_endpoint(c.chip, c.section);
  bool subscribed = false;
  for (const auto& q : server.requests())
    subscribed |= q["method"] == ep.method && q["params"].value("sensor", "") == ep.value;
  CHECK(subscribed);
  const std::string accel = nlohmann::json::parse(r.out)["results"]["files"]["accel"];
  CHECK(static_cast<long>(klipper_csv_rows(accel)) == server.samples_sent());
  const auto fit = run_cli({"resonance", accel, "--axis", "x", "--json"});
  INFO(fit.err);
  REQUIRE(fit.code == 0);
  const auto modes = nlohmann::json::parse(fit.out)["results"]["axes"]["x"]["modes"];
  REQUIRE(!modes.empty());
  CHECK(modes[0]["freq_hz"].get<double>() == Approx(c.f_mode).epsilon(0.01));
}

TEST_CASE("a liquefier step run on Klipper's load cell gives tau within 5 %", "[machine]") {
  const auto dir = scratch_dir("klipper_load_cell");
  const std::string sock = dir + "/klippy_uds";
  const double tau = 0.38, theta = 0.05;
  FakeKlipperConfig fake;
  fake.load_cell = "load_cell extruder";
  FakeKlipper server(sock,
                     tunekit::sim::SimConfig::from_options({fmt::format("tau_s={}", tau), "tau_flow_exponent=0",
                                                            fmt::format("theta_s={}", theta), "K=2.8"}),
                     fake);
  // The profile names Marlin; the protocol is built for Klipper, the firmware identified.
  const auto profile =
      klipper_profile(dir, "accelerometer = false\nload_cell = true\nload_cell_name = \"load_cell extruder\"\n", false);
  const auto r = run_cli(
      {"run", "liquefier-step", "--machine", profile, "--port", "unix:" + sock, "--run-dir", dir + "/run", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  bool force = false, trapq = false;
  for (const auto& q : server.requests()) {
    force |= q["method"] == "load_cell/dump_force" && q["params"].value("load_cell", "") == "extruder";
    trapq |= q["method"] == "motion_report/dump_trapq" && q["params"].value("name", "") == "extruder";
  }
  CHECK(force);
  CHECK(trapq);
  const std::string csv = nlohmann::json::parse(r.out)["results"]["files"]["load_cell"];
  CHECK(static_cast<long>(klipper_csv_rows(csv)) == server.load_cell_samples_sent());
  CHECK(static_cast<long>(klipper_csv_rows(dir + "/run/load_cell_raw.csv")) == server.load_cell_samples_sent());
  // The feed column comes from the extruder's trapq: both feed levels of the protocol appear,
  // as Klipper runs them (each extrude-only move stops at its ends, so its cruise is slightly
  // faster than the level: 1.00017 and 3.0015 mm/s).
  const auto text = tunekit::test::read_text(csv);
  CHECK(text.find(",1.000") != std::string::npos);
  CHECK(text.find(",3.00") != std::string::npos);
  const auto fit =
      run_cli({"step", csv, "--time", "time", "--input", "feed", "--output", "force", "--model", "fopdt", "--json"});
  INFO(fit.err);
  REQUIRE(fit.code == 0);
  const auto p = nlohmann::json::parse(fit.out)["results"]["pooled"]["params"];
  CHECK(p["tau_s"]["value"].get<double>() == Approx(tau).epsilon(0.05));
  CHECK(p["K"]["value"].get<double>() == Approx(2.8).epsilon(0.05));
}

TEST_CASE("an uncalibrated Klipper load cell or an unknown sensor name ends with exit 3 and the journal kept",
          "[machine]") {
  const auto dir = scratch_dir("klipper_load_cell_bad");
  {
    const std::string sock = dir + "/uds1";
    FakeKlipperConfig fake;
    fake.load_cell = "load_cell";
    fake.load_cell_calibrated = false;
    FakeKlipper server(sock, tunekit::sim::SimConfig{}, fake);
    const auto profile = klipper_profile(dir, "load_cell = true\n");
    const auto r =
        run_cli({"run", "liquefier-step", "--machine", profile, "--port", "unix:" + sock, "--run-dir", dir + "/r1"});
    CHECK(r.code == 3);
    CHECK(r.err.find("not calibrated") != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(tunekit::test::read_json(dir + "/r1/run.json")["status"] == "failed");
    CHECK(fs::exists(dir + "/r1/journal.jsonl"));
  }
  {
    const std::string sock = dir + "/uds2";
    FakeKlipperConfig fake;
    fake.accelerometers = {"lis2dw"};
    FakeKlipper server(sock, tunekit::sim::SimConfig{}, fake);
    const auto profile = klipper_profile(dir, "accelerometer = \"lis2dw\"\naccelerometer_name = \"lis2dw toolhead\"\n");
    const auto r =
        run_cli({"run", "axis-sweep", "--machine", profile, "--port", "unix:" + sock, "--run-dir", dir + "/r2"});
    CHECK(r.code == 3);
    CHECK(r.err.find("The value 'toolhead' is not valid for sensor") != std::string::npos);
    CHECK(tunekit::test::read_json(dir + "/r2/run.json")["status"] == "failed");
  }
}

TEST_CASE("a profile naming an accelerometer Klipper does not read is refused with its line", "[machine]") {
  const auto dir = scratch_dir("klipper_bad_chip");
  const auto profile = klipper_profile(dir, "accelerometer = \"bma400\"\n");
  CHECK_THROWS_WITH(tp::load_machine_profile(profile), Catch::Contains("printer.toml:") && Catch::Contains("bma400"));
}
