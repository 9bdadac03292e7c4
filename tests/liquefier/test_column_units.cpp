// Column names as pandas and loggers write them (unit-suffixed snake_case): the time column is
// found by name, the units come from the names (or --input-unit), and a flow in mm^3/s stays a
// flow through `export`, which places the operating points at the logged flows.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

using tunekit::test::run_cli;

namespace {

// Flow steps 2 -> 6 -> 2 -> 4 -> 2 mm^3/s into a first-order force response with dead time.
std::string flow_step_log(const std::string& header) {
  const double fs = 100, K = 1.5, theta = 0.05, tau = 0.3;
  const std::vector<std::pair<double, double>> lv{{0, 2}, {5, 6}, {10, 2}, {15, 4}, {20, 2}};
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0, 0.01);
  std::ostringstream os;
  os << header << "\n";
  double state = K * 2.0;
  for (int i = 0; i < 25 * fs; ++i) {
    const double t = i / fs;
    double u = 0, ud = 2.0;
    for (const auto& [t0, l] : lv) {
      if (t >= t0) u = l;
      if (t - theta >= t0) ud = l;
    }
    state += (K * ud - state) * (1 - std::exp(-(1 / fs) / tau));
    os << t << "," << u << "," << state + noise(rng) << "\n";
  }
  return os.str();
}

}  // namespace

TEST_CASE("tunekit step reads time_s/flow_mm3_s/force_N without --time, and export places points at the logged flows") {
  const std::string dir = tunekit::test::scratch_dir("flow_units");
  const std::string log = tunekit::test::write_scratch("flow_log.csv", flow_step_log("time_s,flow_mm3_s,force_N"));
  const std::string step_json = dir + "/step.json";
  const auto r = run_cli({"step", log, "--input", "flow_mm3_s", "--output", "force_N", "--json", "-o", step_json});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto j = nlohmann::json::parse(r.out);
  CHECK(j["results"]["units"]["input"] == "mm^3/s");
  CHECK(j["results"]["units"]["output"] == "N");
  CHECK(j["options"]["time_column"] == "time_s");
  REQUIRE(j["results"]["operating_points"].size() == 3);  // arrivals at 2, 4 and 6 mm^3/s

  const std::string cfg = dir + "/Configuration_adv.h";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/Configuration_adv.h"), cfg);
  const auto e = run_cli(
      {"export", "-f", "marlin", "-c", cfg, "-p", tunekit::test::dataset("machines/sim.toml"), step_json, "--json"});
  INFO(e.err);
  REQUIRE(e.code == 0);
  const auto ej = nlohmann::json::parse(e.out);
  const auto& sched = ej["results"]["design"]["schedule"];
  REQUIRE(sched.size() == 3);
  // The schedule is at the flows of the log (2, 4 and 6 mm^3/s), not at 2, 4 and 6 mm/s of
  // filament (which would be 2.4 times those flows with 1.75 mm filament).
  CHECK(sched[0]["flow_mm3_s"].get<double>() == Approx(2.0));
  CHECK(sched[1]["flow_mm3_s"].get<double>() == Approx(4.0));
  CHECK(sched[2]["flow_mm3_s"].get<double>() == Approx(6.0));
  CHECK(sched[2]["feed_mm_s"].get<double>() < 6.0 / 2.0);

  // The same log with bare names: --input-unit says what the input is.
  const std::string bare = tunekit::test::write_scratch("flow_log_bare.csv", flow_step_log("t,flow,force"));
  const auto b = run_cli({"step", bare, "--input", "flow", "--output", "force", "--input-unit", "mm3/s", "--json"});
  INFO(b.err);
  REQUIRE(b.code == 0);
  CHECK(nlohmann::json::parse(b.out)["results"]["units"]["input"] == "mm^3/s");

  // No time column by any of its names: one clear line, exit 2.
  const std::string notime = tunekit::test::write_scratch("flow_log_notime.csv", flow_step_log("when,flow,force"));
  const auto n = run_cli({"step", notime, "--input", "flow", "--output", "force"});
  CHECK(n.code == 2);
  CHECK(n.err.find("no time column") != std::string::npos);
  CHECK(n.err.find("--time") != std::string::npos);
}
