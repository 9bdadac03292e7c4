// tunekit profile on real configurations: the TOML it writes loads back with every value commented
// with its source, the JSON carries the sources, declared sensors are added, errors are one line
// with exit 2, and `run --machine printer.cfg` reads a firmware configuration directly.
#include <algorithm>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/machine/machine_profile.hpp"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using tunekit::test::dataset;
using tunekit::test::run_cli;

TEST_CASE("tunekit profile writes a TOML profile that loads back, every value with its source", "[profiles][cli]") {
  const std::string cfg = dataset("klipper_configs/printer-creality-ender3-v2-2020.cfg");
  const std::string out = tunekit::test::scratch_dir("profile_cli") + "/ender3.toml";
  const auto r = run_cli({"profile", cfg, "-o", out, "--sensor", "load_cell"});
  REQUIRE(r.code == 0);
  CHECK_THAT(r.out, Contains("klipper configuration, cartesian kinematics: profile written to"));
  const std::string toml = tunekit::test::read_text(out);
  std::istringstream lines(toml);
  int values = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#' || line[0] == '[') continue;
    INFO(line);
    CHECK(line.find(" = ") != std::string::npos);
    CHECK(line.find("  # ") != std::string::npos);  // every value names its source
    CHECK(line.find("not in the configuration") == std::string::npos);
    ++values;
  }
  CHECK(values > 30);
  CHECK_THAT(toml, Contains("max_accel_mm_s2 = 798.2432411074329  # Klipper default (klippy/kinematics/extruder.py)"));
  const auto p = tunekit::machine::load_machine_profile(out);
  CHECK(p.firmware == "klipper");
  CHECK(p.axis("x").max_mm == 235);
  CHECK(p.extruder.max_accel_mm_s2 == Approx(798.2432).epsilon(1e-6));
  CHECK(p.sensors.load_cell);  // --sensor load_cell
  CHECK_FALSE(p.sensors.accelerometer);
}

TEST_CASE("tunekit profile --json gives the profile and the source of every value", "[profiles][cli]") {
  const auto r = run_cli({"profile", dataset("rrf_configs/prusa-mk3s/config.g"), "--json"});
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["command"] == "profile");
  const auto& res = j["results"];
  CHECK(res["format"] == "rrf");
  CHECK(res["axes"]["x"]["max_mm"] == 250);
  CHECK(res["print"]["max_accel_mm_s2"] == 2500);
  CHECK_THAT(res["sources"]["axes.y.min_mm"].get<std::string>(), Contains("M208 X0:250 Y-4:215 Z-0.1:205"));
}

TEST_CASE("tunekit profile: bad input is one line naming FILE:LINE, exit 2", "[profiles][cli][errors]") {
  const std::string dir = tunekit::test::scratch_dir("profile_cli_errors");
  std::string t = tunekit::test::read_text(dataset("klipper_configs/printer-creality-ender3-v2-2020.cfg"));
  t.replace(t.find("max_accel: 3000"), 15, "max_accel: 1e308");
  const std::string huge = tunekit::test::write_scratch("profile_cli_huge.cfg", t);
  auto r = run_cli({"profile", huge});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, StartsWith("tunekit: error: " + huge + ":93: [printer] max_accel = 1e+308 is not a plausible"));
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  const std::string empty = tunekit::test::write_scratch("profile_cli_empty.cfg", "");
  r = run_cli({"profile", empty});
  CHECK(r.code == 2);
  CHECK(r.err == "tunekit: error: " + empty + ": the file is empty\n");
  const std::string loop = tunekit::test::write_scratch("profile_cli_loop.cfg", "[include profile_cli_loop.cfg]\n");
  r = run_cli({"profile", loop});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, StartsWith("tunekit: error: " + loop + ":1: [include] of"));
  r = run_cli({"profile", dataset("klipper_configs/printer-creality-ender3-v2-2020.cfg"), "--sensor", "radar"});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Contains("--sensor radar"));
}

TEST_CASE("run --machine takes a Klipper printer.cfg directly", "[profiles][cli]") {
  // The print acceleration is set below the stock Ender-3 V2's extrude-only limit (798 mm/s^2, Klipper's
  // default for max_accel 3000): the retractions of the pattern are extrude-only moves.
  const auto r =
      run_cli({"run", "test-pattern", "--machine", dataset("klipper_configs/printer-creality-ender3-v2-2020.cfg"),
               "--dry-run", "-p", "accel_mm_s2=700"});
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK_THAT(r.out, Contains("printer-creality-ender3-v2-2020"));
  CHECK_THAT(r.out, Contains("SET_VELOCITY_LIMIT ACCEL=700"));  // Klipper's dialect, from the imported profile
}
