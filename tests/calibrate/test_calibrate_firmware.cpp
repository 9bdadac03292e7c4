// The main job on each firmware: `tunekit calibrate --machine sim --firmware klipper|marlin|rrf`
// runs the simulated printer with that firmware's planner rules, recommends a shaper the
// firmware has (within its damping bound for that shaper) and writes that firmware's
// configuration. Shaper lists and bounds: Klipper klippy/extras/shaper_defs.py:146-159; Marlin
// classic input shaping is ZV only (M593.cpp); RepRapFirmware src/Movement/AxisShaper.h.
#include <catch2/catch.hpp>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace {

namespace tkp = tunekit::firmware;

struct FirmwareRun {
  std::string dir;
  tunekit::test::CliRun cli;
  nlohmann::json results;
};

FirmwareRun calibrate_firmware(const std::string& name, const std::vector<std::string>& extra) {
  FirmwareRun r;
  r.dir = tunekit::test::scratch_dir(name) + "/run";
  std::vector<std::string> args{"calibrate", "--machine", "sim", "--out", r.dir};
  args.insert(args.end(), extra.begin(), extra.end());
  r.cli = tunekit::test::run_cli(args);
  if (r.cli.code == 0)
    r.results = nlohmann::json::parse(tunekit::read_file_bytes(r.dir + "/results.json")).at("results");
  return r;
}

void check_shapers_are_the_firmwares(const FirmwareRun& r, tkp::ExportFirmware fw) {
  const auto& shapers = r.results.at("compensators").at("settings").at("shapers");
  REQUIRE(shapers.size() >= 1);
  for (const auto& [axis, sh] : shapers.items()) {
    INFO(axis << ": " << sh.dump());
    const auto f = tkp::limits::find_shaper(fw, sh.at("type").get<std::string>());
    REQUIRE(f.has_value());
    CHECK(sh.at("damping").get<double>() <= f->max_damping);
  }
}

}  // namespace

TEST_CASE("calibrate --firmware klipper on heavily damped axes picks Klipper shapers within their damping bounds") {
  // zeta 0.35 on X: above ei's 0.4? no, but above 2hump_ei's 0.3 and 3hump_ei's 0.2; zeta 0.45
  // on Y is above every EI bound: only zv, mzv, zvd remain.
  const auto r = calibrate_firmware("calibrate_klipper_damped", {"--firmware", "klipper", "--skip-liquefier", "--sim",
                                                                 "mode_x=48:0.35", "--sim", "mode_y=37:0.45"});
  INFO(r.cli.err);
  REQUIRE(r.cli.code == 0);
  check_shapers_are_the_firmwares(r, tkp::ExportFirmware::klipper);
  const std::string cfg = tunekit::read_file_bytes(r.dir + "/config/changes.diff");
  CHECK(cfg.find("shaper_type_x") != std::string::npos);
}

TEST_CASE("calibrate --firmware marlin completes and writes Configuration_adv.h with a ZV shaper") {
  const auto r = calibrate_firmware("calibrate_marlin", {"--firmware", "marlin"});
  INFO(r.cli.err);
  REQUIRE(r.cli.code == 0);
  check_shapers_are_the_firmwares(r, tkp::ExportFirmware::marlin);
  const std::string diff = r.results.at("config_diff");
  CHECK(diff.find("SHAPING_FREQ_X") != std::string::npos);
  CHECK(diff.find("ADVANCE_K") != std::string::npos);
  // The simulated printer ran Marlin's planner and answered M115 as Marlin.
  const auto run = nlohmann::json::parse(tunekit::read_file_bytes(r.dir + "/axis-x/run.json"));
  CHECK(run.at("firmware").at("name").get<std::string>().rfind("Marlin", 0) == 0);
}

TEST_CASE("calibrate --firmware rrf completes and writes config.g with an RRF shaper") {
  const auto r = calibrate_firmware("calibrate_rrf", {"--firmware", "rrf"});
  INFO(r.cli.err);
  REQUIRE(r.cli.code == 0);
  check_shapers_are_the_firmwares(r, tkp::ExportFirmware::rrf);
  const std::string diff = r.results.at("config_diff");
  CHECK(diff.find("M593 P\"") != std::string::npos);
  const auto run = nlohmann::json::parse(tunekit::read_file_bytes(r.dir + "/axis-x/run.json"));
  CHECK(run.at("firmware").at("name").get<std::string>().find("RepRapFirmware") != std::string::npos);
}
