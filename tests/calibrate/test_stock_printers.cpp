// The printers users have: every stock printer configuration Klipper ships (its config/printer-*.cfg,
// datasets/klipper_configs) whose kinematics tunekit supports is imported as Klipper computes its
// limits, and calibrate's plan with default settings is built and checked against those limits,
// on the load-cell path (the technician declares the accelerometer and the load cell the stock
// file does not list) and on the camera path (an accelerometer only). A refusal is allowed only
// where the message names a physical reason, and each one is listed here.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include "test_support.hpp"
#include "tunekit/calibration/guided/calibration_pipeline.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace {

namespace fs = std::filesystem;
using tunekit::calibration::CalibrateArgs;
using tunekit::calibration::CalibrationProfile;

/// The stock files, sorted, with their [printer] kinematics as the file writes it.
std::vector<std::pair<std::string, std::string>> stock_configs() {
  std::vector<std::pair<std::string, std::string>> out;
  const std::regex kin(R"(^\s*kinematics\s*[:=]\s*(\w+))");
  for (const auto& entry : fs::directory_iterator(tunekit::test::dataset("klipper_configs"))) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("printer-", 0) != 0 || entry.path().extension() != ".cfg") continue;
    std::ifstream in(entry.path());
    std::string line, kinematics;
    std::smatch m;
    while (kinematics.empty() && std::getline(in, line))
      if (std::regex_search(line, m, kin)) kinematics = m[1];
    out.emplace_back(entry.path().string(), kinematics);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool supported(const std::string& kinematics) {
  return kinematics == "cartesian" || kinematics == "corexy" || kinematics == "delta";
}

/// calibrate --machine sim --profile FILE --dry-run with the sensors declared: "" when the plan
/// holds, else the refusal.
std::string plan_refusal(const std::string& path, const std::vector<std::string>& sensors) {
  tunekit::machine::ProfileImportOptions io;
  io.sensors = sensors;
  CalibrateArgs a;
  a.machine = "sim";
  a.profile = path;
  a.dry_run = true;
  try {
    const CalibrationProfile profile{tunekit::machine::import_machine_profile(path, io), path, {}};
    const auto plan = tunekit::calibration::plan_calibration(a, profile, false);
    for (const auto& e : plan.experiments)
      if (!(e.estimated_s > 0)) return e.name + " has no machine time";
    return "";
  } catch (const tunekit::Error& e) {
    return e.formatted();
  }
}

// The refusals allowed, by file: each names the physical reason in its message. The 2019 Anet A8's
// file lets Z go no lower than 0.5 mm (position_min), above the 0.2 mm at which the camera path
// prints its lines. (The Creality CR-30, a belt printer whose Z Klipper's file gives 20,000,000 mm,
// imports with that endless axis ending at the profile's 10 m range, and plans.)
const std::map<std::string, std::string> kAllowedRefusals = {
    {"printer-anet-a8-2019.cfg", "z position 0.2 mm is outside the travel 0.5..350 mm"}};

/// Whether `why` (empty: planned) is what the test allows for the file: planned, or refused for
/// its listed reason.
bool as_allowed(const std::string& path, const std::string& why) {
  const auto allowed = kAllowedRefusals.find(fs::path(path).filename().string());
  return why.empty() || (allowed != kAllowedRefusals.end() && why.find(allowed->second) != std::string::npos);
}

}  // namespace

TEST_CASE("every Klipper stock printer's calibration plan holds with default settings (load cell)",
          "[stock][repeats]") {
  std::size_t checked = 0;
  std::vector<std::string> refused;  // refusals other than the allowed ones
  for (const auto& [path, kinematics] : stock_configs()) {
    if (!supported(kinematics)) continue;
    ++checked;
    const std::string why = plan_refusal(path, {"accelerometer", "load_cell"});
    if (!as_allowed(path, why)) refused.push_back(fs::path(path).filename().string() + ": " + why);
  }
  CHECK(checked >= 100);
  std::string all;
  for (const auto& r : refused) all += r + "\n";
  INFO(all);
  CHECK(refused.empty());
}

TEST_CASE("every Klipper stock printer's calibration plan holds with default settings (camera path)",
          "[stock][repeats]") {
  std::size_t checked = 0;
  std::vector<std::string> unexpected;
  for (const auto& [path, kinematics] : stock_configs()) {
    if (!supported(kinematics)) continue;
    ++checked;
    const std::string why = plan_refusal(path, {"accelerometer"});
    if (!as_allowed(path, why))
      unexpected.push_back(fs::path(path).filename().string() + ": " + (why.empty() ? "(planned)" : why));
  }
  CHECK(checked >= 100);
  CHECK(kAllowedRefusals.size() <= 4);
  std::string all;
  for (const auto& r : unexpected) all += r + "\n";
  INFO(all);
  CHECK(unexpected.empty());
}

TEST_CASE(
    "calibrate --sensor with a profile it cannot read says why it cannot read it, and a TOML profile is refused") {
  const std::string dir = tunekit::test::scratch_dir("sensor_profile_errors");
  const auto missing = tunekit::test::run_cli({"calibrate", "--machine", "sim", "--profile", dir + "/missing.cfg",
                                               "--sensor", "accelerometer", "--dry-run", "--out", dir + "/run"});
  CHECK(missing.code == 2);
  CHECK(missing.err.find("cannot open") != std::string::npos);
  CHECK(missing.err.find("--sensor declares") == std::string::npos);
  const auto toml =
      tunekit::test::run_cli({"calibrate", "--machine", "sim", "--profile", tunekit::test::dataset("machines/sim.toml"),
                              "--sensor", "accelerometer", "--dry-run", "--out", dir + "/run2"});
  CHECK(toml.code == 2);
  CHECK(toml.err.find("--sensor declares sensors a firmware configuration does not list") != std::string::npos);
}
