// Intervals and verdicts on the simulator's own runs: the step and frequency-response taus are
// never said to disagree on any firmware's planner (on the desktop default, whose tau falls with
// the flow: the chirp's tau is held against the step trend over the chirp's feeds, and on the
// peek preset, one first-order plant at every flow), and the single analyses (step, freq,
// resonance) of a clean simulated run warn about nothing (on the peek preset: on the desktop
// default the pooled step fit rightly warns that the levels do not share one tau).
#include <filesystem>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/file_bytes.hpp"

using tunekit::read_file_bytes;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;

namespace {

std::string sim_run(const std::string& name, const std::vector<std::string>& extra, const std::string& preset) {
  const std::string dir = scratch_dir(name) + "/run";
  std::vector<std::string> args{"calibrate", "--machine", "sim", "--sim", "preset=" + preset, "--out", dir};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_cli(args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("do NOT agree") == std::string::npos);
  return dir;
}

}  // namespace

TEST_CASE("calibrate on each firmware's simulated planner never says the step and frequency taus do NOT agree",
          "[repeats]") {
  const std::string fw = GENERATE(as<std::string>{}, "marlin", "rrf", "klipper");
  const std::string preset = GENERATE(as<std::string>{}, "desktop", "peek");
  INFO("firmware " << fw << ", preset " << preset);
  const std::string dir = sim_run("calibrate_agree_" + fw + "_" + preset, {"--firmware", fw, "--skip-axes"}, preset);
  const auto env = nlohmann::json::parse(read_file_bytes(dir + "/results.json"));
  const auto& agreement = env.at("results").at("agreement");
  REQUIRE(agreement.size() == 1);
  INFO(agreement[0].dump());
  CHECK(agreement[0].at("verdict") != "differ");
  CHECK(agreement[0].at("agree").get<bool>());
  CHECK(agreement[0].at("margin").at("relative").get<double>() == Approx(0.02));
  for (const auto& w : env.at("warnings")) CHECK(w.get<std::string>().find("do NOT agree") == std::string::npos);
}

TEST_CASE("the simulator's clean runs through step and freq and resonance print no warning") {
  const std::string dir = sim_run("calibrate_clean_analyses", {}, "peek");
  std::vector<std::vector<std::string>> commands{
      {"step", dir + "/liquefier-step/step.csv", "--input", "feed", "--output", "force"},
      {"freq", dir + "/liquefier-chirp/feed_force.csv", "--input", "feed", "--output", "force"},
      {"resonance", dir + "/axis-x/raw_data_x_tunekit.csv"},
      {"resonance", dir + "/axis-y/raw_data_y_tunekit.csv"}};
  for (auto args : commands) {
    INFO(args[0] << " " << args[1]);
    auto text = run_cli(args);
    INFO(text.err);
    REQUIRE(text.code == 0);
    CHECK(text.err.find("warning") == std::string::npos);
    CHECK(text.out.find("warning") == std::string::npos);
    args.push_back("--json");
    const auto json = run_cli(args);
    REQUIRE(json.code == 0);
    const auto env = nlohmann::json::parse(json.out);
    INFO(env.at("warnings").dump());
    CHECK(env.at("warnings").empty());
  }
}

TEST_CASE("calibrate fits the axes against their commanded motion, and the 95 % intervals hold the simulator's modes") {
  const auto& run = tunekit::test::default_calibration();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const auto results = tunekit::test::read_json(run.dir + "/results.json").at("results");
  for (const char* axis : {"x", "y"}) {
    INFO("axis " << axis);
    const auto& a = results.at("axes").at(axis);
    const std::string dir = run.dir + "/axis-" + axis;
    CHECK(std::filesystem::exists(dir + "/commanded_motion_" + axis + "_tunekit.csv"));
    CHECK(a.at("fit").at("method") == "output_error");
    const auto truth = tunekit::test::read_json(dir + "/truth.json").at("axes").at(axis).at("modes").at(0);
    const auto& m = a.at("modes").at(a.at("fit").at("dominant_mode").get<int>());
    INFO(m.dump() << "\ntruth " << truth.dump());
    const double f = truth.at("freq_hz"), zeta = truth.at("zeta");
    CHECK(m.at("freq_ci95").at(0).get<double>() <= f);
    CHECK(m.at("freq_ci95").at(1).get<double>() >= f);
    CHECK(m.at("zeta_ci95").at(0).get<double>() <= zeta);
    CHECK(m.at("zeta_ci95").at(1).get<double>() >= zeta);
    // The sensor's noise alone: the intervals are hundreds of times narrower than the spectrum's.
    const double hw = 0.5 * (m.at("freq_ci95").at(1).get<double>() - m.at("freq_ci95").at(0).get<double>());
    const auto& s = a.at("fit").at("spectrum_fit").at("modes").at(0);
    CHECK(hw < 0.01 * 0.5 * (s.at("freq_ci95").at(1).get<double>() - s.at("freq_ci95").at(0).get<double>()));
    // The residuals are the sensor's noise, 20 mm/s^2 rms, and white.
    CHECK(a.at("fit").at("diagnostics").at("rms").get<double>() == Approx(20).epsilon(0.02));
    CHECK(a.at("fit").at("variance_inflation").get<double>() < 1.1);
  }
}
