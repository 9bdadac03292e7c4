// Reproducing calibrate's analyses: results.json names, for every analysis calibrate made, the
// command that makes it again from the run directory's files; run as a user would run it, it
// gives calibrate's numbers.
#include <catch2/catch.hpp>

#include <filesystem>
#include <set>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"

namespace calibrate_reproduce_test {

namespace fs = std::filesystem;

struct CalibrateRun {
  std::string dir;
  tunekit::test::CliRun cli;
  nlohmann::json results;
};

// The default calibration the tests that only read it share (test_support.hpp).
CalibrateRun shared_run() {
  const auto& shared = tunekit::test::default_calibration();
  CalibrateRun r{shared.dir, shared.cli, {}};
  if (r.cli.code == 0) r.results = tunekit::test::read_json(r.dir + "/results.json").at("results");
  return r;
}

// The reproduce entry of `analysis`, or null.
const nlohmann::json* entry(const nlohmann::json& results, const std::string& analysis) {
  for (const auto& e : results.at("reproduce"))
    if (e.at("analysis") == analysis) return &e;
  return nullptr;
}

// Runs a reproduce command as a user would (--json added) and returns its results.
nlohmann::json reproduce(const std::string& run_dir, const std::string& command) {
  const auto cli = tunekit::test::run_reproduce_command(run_dir, command, {"--json"});
  INFO(command << "\n" << cli.err);
  REQUIRE(cli.code == 0);
  return nlohmann::json::parse(cli.out).at("results");
}

void check_axis_reproduced(const char* axis) {
  const auto run = shared_run();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const auto* e = entry(run.results, std::string("shaper_") + axis);
  REQUIRE(e != nullptr);
  const std::string command = e->at("command").get<std::string>();
  INFO(command);
  CHECK(command.find("--axis " + std::string(axis)) != std::string::npos);
  const auto mine = reproduce(run.dir, command).at("axes").at(axis);
  const auto& cal = run.results.at("axes").at(axis);
  const auto mode = [](const nlohmann::json& axis_results, const char* key) {
    return axis_results.at("modes").at(0).at(key).get<double>();
  };
  const auto shaper_freq = [](const nlohmann::json& axis_results) {
    return axis_results.at("recommended").at("freq_hz").get<double>();
  };
  // One pipeline: the same files (the record and the commanded motion beside it) give the same modes.
  CHECK(mine.at("fit").at("method") == cal.at("fit").at("method"));
  CHECK(mode(mine, "freq_hz") == Approx(mode(cal, "freq_hz")).epsilon(1e-12));
  CHECK(mode(mine, "zeta") == Approx(mode(cal, "zeta")).epsilon(1e-12));
  CHECK(shaper_freq(mine) == Approx(shaper_freq(cal)).epsilon(0.01));
  CHECK(mine.at("recommended").at("type") == cal.at("recommended").at("type"));
}

}  // namespace calibrate_reproduce_test

TEST_CASE("calibrate's reproduce command for x gives its resonance and damping, and its shaper frequency within 1 %") {
  calibrate_reproduce_test::check_axis_reproduced("x");
}

TEST_CASE("calibrate's reproduce command for y gives its resonance and damping, and its shaper frequency within 1 %") {
  calibrate_reproduce_test::check_axis_reproduced("y");
}

TEST_CASE("calibrate names a reproduce command for every analysis it made, and the analysis README lists them") {
  const auto run = calibrate_reproduce_test::shared_run();
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  std::set<std::string> analyses;
  const std::string readme = tunekit::read_file_bytes(run.dir + "/analysis/README");
  for (const auto& e : run.results.at("reproduce")) {
    const std::string name = e.at("analysis").get<std::string>(), command = e.at("command").get<std::string>();
    INFO(name << ": " << command);
    CHECK(analyses.insert(name).second);
    // The analysis' own JSON is in the run directory, and its input is named relative to it.
    CHECK(std::filesystem::exists(run.dir + "/" + e.at("json").get<std::string>()));
    CHECK(command.find(run.dir) == std::string::npos);
    CHECK(readme.find(command) != std::string::npos);
  }
  // Every analysis calibrate made has its JSON in analysis/: each one is named once.
  std::set<std::string> made;
  for (const auto& f : std::filesystem::directory_iterator(run.dir + "/analysis"))
    if (f.path().extension() == ".json" && f.path().stem() != "export") made.insert(f.path().stem().string());
  CHECK(analyses == made);
  CHECK(analyses == std::set<std::string>{"step", "freq", "shaper_x", "shaper_y"});
}
