// End to end: `tunekit calibrate --machine sim` runs the liquefier flow sweep; on the simulator's
// physics liquefier (pressure-driven power-law melt through the nozzle, whose time constant
// tau = C k n Q^(n-1) falls with the flow Q) it recovers the true tau at each level.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/protocols/experiment_design.hpp"

using tunekit::read_file_bytes;

TEST_CASE("calibrate's flow sweep on the physics liquefier recovers the true tau at each level within 5 %") {
  const std::string dir = tunekit::test::scratch_dir("calibrate_flow_sweep") + "/run";
  const auto cli = tunekit::test::run_cli(
      {"calibrate", "--machine", "sim", "--skip-axes", "--sim", "liquefier=physics", "--out", dir});
  INFO(cli.err);
  REQUIRE(cli.code == 0);
  const auto env = nlohmann::json::parse(read_file_bytes(dir + "/results.json"));
  const auto& step = env.at("results").at("liquefier").at("step");
  const auto truth = nlohmann::json::parse(read_file_bytes(dir + "/liquefier-step/truth.json")).at("liquefier");
  REQUIRE(truth.at("model") == "physics");
  const double C = truth.at("compliance_mm3_MPa").get<double>(), k = truth.at("k_MPa_s^n_per_mm3^n").get<double>(),
               n = truth.at("n_index").get<double>(), area = truth.at("filament_area_mm2").get<double>();
  // The linearised time constant of C dP/dt = A u - (P/k)^(1/n) at the flow Q.
  auto true_tau = [&](double q) { return C * k * n * std::pow(q, n - 1); };

  // The protocol that ran: the design's levels (experiment_design.hpp) up to 90 % of the
  // profile's max_flow_mm3_s (15 mm^3/s).
  const auto& levels = step.at("operating_points");
  int both = 0;
  double qmax = 0;
  for (const auto& l : levels) {
    const double q = l.at("flow_mm3_s").get<double>();
    CHECK(q == Approx(l.at("u").get<double>() * area));
    qmax = std::max(qmax, q);
    if (l.at("n_rising").get<int>() == 0 || l.at("n_falling").get<int>() == 0) continue;
    ++both;
    const double tau = l.at("tau_s").get<double>();
    INFO("flow " << q << " mm^3/s: tau " << tau << " s, truth " << true_tau(q) << " s");
    CHECK(tau == Approx(true_tau(q)).epsilon(0.05));
  }
  CHECK(both == tunekit::protocols::kFlowLevels);
  CHECK(qmax == Approx(13.5).epsilon(0.02));
  // The trend's exponent: tau = C k n Q^(n-1), so b = n - 1.
  const auto& b = step.at("trend").at("tau_s");
  INFO("b = " << b.at("b").get<double>());
  CHECK(b.at("b").get<double>() == Approx(n - 1).margin(0.05));
  // Export designed from the operating points, the arrival levels (flow-dependent advance).
  const auto& schedule = env.at("results").at("compensators").at("design").at("schedule");
  CHECK(schedule.size() == levels.size());
  // The load cell reads the melt pressure, the stored volume C P over the compliance: V(Q) is
  // measured at every level, so the advance V(Q)/Q = C k Q^(n-1) carries the model's own 95 %
  // interval, not a band over an unmeasured low-flow melt.
  const auto& comp = env.at("results").at("compensators");
  const double q = comp.at("design").at("design_feed_mm_s").get<double>() * area;
  const double k_true = C * k * std::pow(q, n - 1);
  const double pa = comp.at("settings").at("pa_k_s").get<double>();
  const double lo = comp.at("pa_k_ci95").at(0).get<double>(), hi = comp.at("pa_k_ci95").at(1).get<double>();
  INFO("advance " << pa << " [" << lo << ", " << hi << "] s at " << q << " mm^3/s, truth " << k_true << " s");
  CHECK(lo <= k_true);
  CHECK(hi >= k_true);
  CHECK(hi - lo < 0.05 * pa);
  CHECK(comp.at("flow_advance").at("band_is_interval") == true);
}

TEST_CASE("tunekit step with the run's feed track reproduces calibrate's liquefier fits within 1 %") {
  const auto& run = tunekit::test::default_calibration();
  const std::string& dir = run.dir;
  INFO(run.cli.err);
  REQUIRE(run.cli.code == 0);
  const auto env = nlohmann::json::parse(read_file_bytes(dir + "/results.json"));
  const auto& cal = env.at("results").at("liquefier").at("step").at("pooled").at("params");
  // The command results.json names for the step analysis, run as a user types it (the load
  // cell's log and the commanded feed track named relative to the run directory, only the
  // columns given besides).
  std::string command;
  for (const auto& e : env.at("results").at("reproduce"))
    if (e.at("analysis") == "step") command = e.at("command").get<std::string>();
  INFO(command);
  CHECK(command ==
        "tunekit step liquefier-step/step.csv --input feed --output force --feed-track liquefier-step/feed_track.csv");
  const auto step = tunekit::test::run_reproduce_command(dir, command, {"--json"});
  INFO(step.err);
  REQUIRE(step.code == 0);
  const auto mine = nlohmann::json::parse(step.out).at("results");
  CHECK(mine.at("steps").size() == env.at("results").at("liquefier").at("step").at("steps").size());
  for (const char* name : {"tau_s", "K", "theta_s"}) {
    const double own = mine.at("pooled").at("params").at(name).at("value").get<double>(),
                 theirs = cal.at(name).at("value").get<double>();
    INFO(name << ": tunekit step " << own << ", calibrate " << theirs);
    CHECK(own == Approx(theirs).epsilon(0.01));
  }
  // The whole-record model, which calibrate's summary lists, driven by the same track.
  const auto& wr = env.at("results").at("liquefier").at("step").at("whole_record");
  CHECK(mine.at("whole_record").at("input_track").at("used") == true);
  for (const char* name : {"tau_ref_s", "b", "theta_s"}) {
    const double own = mine.at("whole_record").at(name).at("value").get<double>(),
                 theirs = wr.at(name).at("value").get<double>();
    INFO(name << ": tunekit step " << own << ", calibrate " << theirs);
    CHECK(own == Approx(theirs).epsilon(0.01));
  }
}
