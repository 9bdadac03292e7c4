// A Z sweep recorded in Klipper's raw format (TEST_RESONANCES AXIS=Z writes raw_data_z_<name>.csv,
// D. Butyugin, Klipper, October 2025) analysed by `tunekit resonance` / `tunekit shaper` and its
// shaper exported into a Klipper printer.cfg as shaper_type_z / shaper_freq_z / damping_ratio_z;
// the firmwares that take no Z shaper from tunekit refuse it with exit 2.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "synth_sweep.hpp"
#include "test_support.hpp"

using tunekit::test::run_cli;
using tunekit::test::SweepSpec;
using tunekit::test::SynthMode;

namespace {

// Klipper's Z test defaults: accel_per_hz_z 15 mm/s^2/Hz up to max_freq_z 100 Hz; swept here
// from 20 Hz at 2 Hz/s to keep the test short. The bed/gantry mode is at 63 Hz.
const std::vector<SynthMode> kTruthZ = {{63.0, 0.05, 1.0}};

SweepSpec z_sweep() {
  SweepSpec s;
  s.f_start_hz = 20;
  s.f_end_hz = 100;
  s.hz_per_sec = 2;
  s.accel_per_hz = 15;
  s.noise_mm_s2 = 25;
  s.seed = 33;
  return s;
}

// The accelerometer's Z channel carries the motion (and gravity); X sees noise, Y noise and 5 % of
// the motion. Written into the calling test's own directory: ctest runs the cases in parallel.
std::string z_file(const std::string& dir) {
  static const std::string csv = [] {
    auto r = tunekit::test::synth_sweep(kTruthZ, z_sweep());
    for (std::size_t i = 0; i < r.t.size(); ++i) {
      const double motion = r.ax[i];
      r.ax[i] = r.az[i] - 9806.65;
      r.az[i] = motion + 9806.65;
    }
    return tunekit::test::to_klipper_csv(r);
  }();
  const std::string path = dir + "/raw_data_z_zaxis.csv";
  std::ofstream(path, std::ios::binary) << csv;
  return path;
}

std::string copy_config(const std::string& test, const std::string& dataset_name) {
  const std::string dir = tunekit::test::scratch_dir(test);
  const std::string cfg = dir + "/" + std::filesystem::path(dataset_name).filename().string();
  std::filesystem::copy_file(tunekit::test::dataset(dataset_name), cfg,
                             std::filesystem::copy_options::overwrite_existing);
  return cfg;
}

}  // namespace

TEST_CASE("a Klipper raw Z sweep is analysed as axis z and its resonance recovered", "[resonance][z]") {
  const std::string dir = tunekit::test::scratch_dir("z_resonance");
  const auto r = run_cli({"resonance", z_file(dir), "--json", "--fit-min", "20", "--fit-max", "100"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto axes = nlohmann::json::parse(r.out)["results"]["axes"];
  REQUIRE(axes.contains("z"));
  CHECK(axes.size() == 1);
  const auto& modes = axes["z"]["modes"];
  REQUIRE(modes.size() >= 1);
  CHECK(std::abs(modes[0]["freq_hz"].get<double>() / kTruthZ[0].freq_hz - 1) < 0.01);
  CHECK(std::abs(modes[0]["zeta"].get<double>() / kTruthZ[0].zeta - 1) < 0.25);
}

TEST_CASE("a Z shaper from a Klipper raw Z sweep is written into printer.cfg as Klipper's Z keys, nothing else",
          "[resonance][z]") {
  const std::string dir = tunekit::test::scratch_dir("z_shaper_export");
  const std::string results = dir + "/shaper.json";
  const auto sh = run_cli({"shaper", z_file(dir), "--klipper-compatible", "--json", "-o", results});
  INFO(sh.err);
  REQUIRE(sh.code == 0);
  const auto rec = nlohmann::json::parse(sh.out)["results"]["axes"]["z"]["recommended"];
  REQUIRE(rec.is_object());
  const double f = rec["freq_hz"].get<double>();
  // The recommended frequency lies near the resonance (Klipper's shapers sit within ~30 % of it).
  CHECK(f > 0.7 * kTruthZ[0].freq_hz);
  CHECK(f < 1.3 * kTruthZ[0].freq_hz);

  const std::string cfg = copy_config("z_shaper_export_cfg", "firmware/printer.cfg");
  const std::string before = tunekit::test::read_text(cfg);
  const auto e = run_cli({"export", "-f", "klipper", "-c", cfg, results, "--no-pa", "--write", "--json"});
  INFO(e.out << e.err);
  REQUIRE(e.code == 0);
  const auto env = nlohmann::json::parse(e.out);
  const std::string after = tunekit::test::read_text(cfg);
  // The written values are the recommendation's, formatted as export writes them.
  const auto& z = env["results"]["settings"]["shapers"]["z"];
  CHECK(z["firmware_type"] == rec["type"]);
  CHECK(z["freq_hz"].get<double>() == Approx(f));
  // The file's [input_shaper] lives in the SAVE_CONFIG block: the three Z keys are added there,
  // right after the section's last line; every other byte is the original's.
  const std::string anchor = "#*# shaper_freq_x = 48.6\n";
  const auto at = before.find(anchor);
  REQUIRE(at != std::string::npos);
  const std::string head = before.substr(0, at + anchor.size());
  REQUIRE(after.size() > before.size());
  REQUIRE(after.compare(0, head.size(), head) == 0);
  const std::string tail = before.substr(at + anchor.size());
  REQUIRE(after.compare(after.size() - tail.size(), tail.size(), tail) == 0);
  const std::string added = after.substr(head.size(), after.size() - head.size() - tail.size());
  char freq[32];
  std::snprintf(freq, sizeof freq, "%.1f", f);
  std::string freq_text = freq;
  if (freq_text.size() > 2 && freq_text.substr(freq_text.size() - 2) == ".0") freq_text.resize(freq_text.size() - 2);
  CHECK(added == "#*# shaper_type_z = " + rec["type"].get<std::string>() + "\n#*# shaper_freq_z = " + freq_text +
                     "\n#*# damping_ratio_z = 0.1\n");
  // The runtime command and the version note come with it.
  CHECK(env["results"]["export"]["gcode"].get<std::string>().find("SHAPER_TYPE_Z=") != std::string::npos);
  CHECK(env.dump().find("Z-axis input shaper") != std::string::npos);
  // A second export changes nothing.
  const auto again = run_cli({"export", "-f", "klipper", "-c", cfg, results, "--no-pa", "--write"});
  CHECK(again.code == 0);
  CHECK(tunekit::test::read_text(cfg) == after);
}

TEST_CASE("a Z shaper is refused with exit 2 for Marlin, RepRapFirmware and Kalico, and the file is left alone",
          "[resonance][z]") {
  const std::vector<std::pair<std::string, std::string>> targets = {
      {"marlin", "firmware/Configuration_adv.h"}, {"rrf", "firmware/config.g"}, {"kalico", "firmware/printer.cfg"}};
  for (const auto& [fw, file] : targets) {
    const std::string cfg = copy_config("z_refused_" + fw, file);
    const std::string before = tunekit::test::read_text(cfg);
    const auto r = run_cli({"export", "-f", fw, "-c", cfg, "--shaper-z", "zv:60:0.1", "--write"});
    INFO(fw << ": " << r.err);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::StartsWith("tunekit: error:"));
    CHECK_THAT(r.err, Catch::Contains("Z shaper is exported for Klipper only"));
    CHECK(tunekit::test::read_text(cfg) == before);
  }
  // Klipper takes the same option.
  const std::string cfg = copy_config("z_refused_klipper", "firmware/printer.cfg");
  const auto k = run_cli({"export", "-f", "klipper", "-c", cfg, "--shaper-z", "zv:60:0.1", "--write"});
  INFO(k.err);
  CHECK(k.code == 0);
  CHECK(tunekit::test::read_text(cfg).find("#*# shaper_freq_z = 60\n") != std::string::npos);
}
