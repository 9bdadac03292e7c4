// The whole-record liquefier model through the commands: `tunekit step` reports it beside the
// per-step fits, `tunekit export` designs the advance V(Q)/Q from it, and `tunekit calibrate` on
// the simulator's physics liquefier agrees with its own per-level fits.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "synth_store.hpp"
#include "test_support.hpp"
#include "tunekit/core/file_bytes.hpp"

using namespace tunekit;
using test::StoreTruth;
using test::synth_store;

namespace {

std::string store_log(const test::StoreRecord& s, const std::string& name) {
  std::ostringstream os;
  os.precision(10);
  os << "time_s,flow_mm3_s,outflow_mm3_s\n";
  for (std::size_t i = 0; i < s.rec.t.size(); ++i) os << s.rec.t[i] << "," << s.rec.u[i] << "," << s.rec.y[i] << "\n";
  return test::write_scratch(name, os.str());
}

/// `tunekit step` then `tunekit export -f klipper` at the design flow; returns export's results.
nlohmann::json step_then_export(const std::string& log, const std::string& dir, double design_flow,
                                nlohmann::json* step_results, bool profile_intervals = false) {
  std::vector<std::string> args{"step",          log,      "--input", "flow_mm3_s",      "--output",
                                "outflow_mm3_s", "--json", "-o",      dir + "/step.json"};
  if (profile_intervals) args.push_back("--profile-intervals");
  const auto r = test::run_cli(args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  if (step_results) *step_results = nlohmann::json::parse(r.out).at("results");
  std::filesystem::copy_file(test::dataset("firmware/printer.cfg"), dir + "/printer.cfg",
                             std::filesystem::copy_options::overwrite_existing);
  const auto e = test::run_cli({"export", "-f", "klipper", "-c", dir + "/printer.cfg", dir + "/step.json",
                                "--design-flow", std::to_string(design_flow), "--json"});
  INFO(e.err);
  REQUIRE(e.code == 0);
  return nlohmann::json::parse(e.out).at("results");
}

}  // namespace

TEST_CASE("export designs the advance V(Q)/Q of the whole-record model, within half its bounds of the truth's") {
  const StoreTruth tr;
  const auto s = synth_store(tr, 25.0, 60.0, 0.02, 31);
  const std::string dir = test::scratch_dir("store_export_nonlinear");
  nlohmann::json step;
  const double qd = 8.0;
  // --profile-intervals: b's and theta's intervals by profile likelihood (default: widened Wald).
  const auto ex = step_then_export(store_log(s, "store_nonlinear.csv"), dir, qd, &step, true);
  const auto& wr = step.at("whole_record");
  REQUIRE(wr.contains("a"));
  CHECK(wr.at("linear_chosen") == false);
  CHECK(wr.at("b").at("ci95_method") == "profile-likelihood");
  CHECK(wr.at("theta_s").at("ci95_method") == "profile-likelihood");
  const double truth = tr.volume(qd) / qd;
  const double k = ex.at("settings").at("pa_k_s").get<double>();
  INFO("exported K " << k << " s, truth V(Q)/Q " << truth << " s");
  // This record does not start at rest: the melt below its lowest level is bounded (tau held there,
  // the power law to zero flow) and K is the middle of the two. This store follows the power law
  // down to zero flow, so its truth is near the upper bound: K is within half the bounds' span of
  // it (and within 15 %), and above the lower bound's K.
  const auto& bounds = ex.at("flow_advance").at("single").at("K_bounds_s");
  const double k_lo = bounds.at(0).get<double>(), k_hi = bounds.at(1).get<double>();
  INFO("bounds [" << k_lo << ", " << k_hi << "] s");
  CHECK(k == Approx(0.5 * (k_lo + k_hi)).epsilon(1e-9));
  CHECK(std::abs(k - truth) < 0.5 * (k_hi - k_lo) + 0.03 * truth);
  CHECK(std::abs(k - truth) < 0.15 * truth);
  // Its 95 % interval holds the truth; most of the melt at 8 mm^3/s is stored below the lowest
  // level (4 mm^3/s), so the interval's lower end holds tau there and lies well below K.
  REQUIRE(ex.contains("pa_k_ci95"));
  const double lo = ex.at("pa_k_ci95").at(0).get<double>(), hi = ex.at("pa_k_ci95").at(1).get<double>();
  INFO("interval [" << lo << ", " << hi << "] s");
  CHECK(lo <= truth);
  CHECK(hi >= truth);
  CHECK(lo < 0.9 * k);
  CHECK(ex.at("flow_advance").at("single").at("low_flow_share").get<double>() > 0.3);
}

TEST_CASE("on a linear liquefier's record the exported advance equals tau within 2 %") {
  StoreTruth tr;
  tr.a = 0.3;
  tr.b = 0;
  const auto s = synth_store(tr, 100.0, 40.0, 0.02, 33);
  const std::string dir = test::scratch_dir("store_export_linear");
  nlohmann::json step;
  const auto ex = step_then_export(store_log(s, "store_linear.csv"), dir, 8.0, &step);
  CHECK(step.at("whole_record").at("linear_chosen") == true);
  const double k = ex.at("settings").at("pa_k_s").get<double>();
  INFO("exported K " << k << " s, tau 0.3 s");
  CHECK(k == Approx(0.3).epsilon(0.02));
}

TEST_CASE("tunekit step prints the whole-record model beside the per-step fits") {
  const StoreTruth tr;
  const auto s = synth_store(tr, 25.0, 30.0, 0.02, 35);
  const auto r =
      test::run_cli({"step", store_log(s, "store_text.csv"), "--input", "flow_mm3_s", "--output", "outflow_mm3_s"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.out.find("whole record: tau = a u^b") != std::string::npos);
  CHECK(r.out.find("step fits disagree with it") != std::string::npos);
}

TEST_CASE("a tau trend falling faster than 1/Q gets an advance from the measured levels with a plain reason") {
  // A step result whose level trend has b = -1.37 (no finite stored volume from zero flow) and no
  // whole-record model: export designs from the levels and says why, naming no formula.
  nlohmann::json ops = nlohmann::json::array();
  const double flows[] = {4, 6, 9, 14};
  for (double q : flows) {
    const double tau = 4.654 * std::pow(q, -1.368);
    ops.push_back({{"u", q},
                   {"flow_mm3_s", q},
                   {"K", 0.95},
                   {"tau_s", tau},
                   {"theta_s", 0.1},
                   {"tau_ci95", {0.9 * tau, 1.1 * tau}}});
  }
  const nlohmann::json env{
      {"schema_version", 1},
      {"command", "step"},
      {"results",
       {{"pooled",
         {{"params",
           {{"K", {{"value", 0.95}, {"stderr", 0.01}, {"ci95", {0.93, 0.97}}, {"unit", "1"}}},
            {"tau_s", {{"value", 0.3}, {"stderr", 0.01}, {"ci95", {0.28, 0.32}}, {"unit", "s"}}},
            {"theta_s", {{"value", 0.1}, {"stderr", 0.01}, {"ci95", {0.08, 0.12}}, {"unit", "s"}}}}}}},
        {"operating_points", ops},
        {"trend", {{"tau_s", {{"a", 4.654138102488328}, {"b", -1.368274786980899}}}}},
        {"units", {{"input", "mm^3/s"}, {"output", "mm^3/s"}}}}}};
  const std::string dir = test::scratch_dir("trend_below_minus_one");
  const std::string path = test::write_scratch("trend_below_minus_one.json", env.dump());
  std::filesystem::copy_file(test::dataset("firmware/printer.cfg"), dir + "/printer.cfg",
                             std::filesystem::copy_options::overwrite_existing);
  const auto e = test::run_cli({"export", "-f", "klipper", "-c", dir + "/printer.cfg", path, "--json"});
  INFO(e.err);
  CHECK(e.err.find("must be positive") == std::string::npos);
  CHECK(e.err.find("b above -1") == std::string::npos);
  REQUIRE(e.code == 0);
  const auto j = nlohmann::json::parse(e.out);
  const double k = j.at("results").at("settings").at("pa_k_s").get<double>();
  CHECK(k > 0);
  bool reason = false;
  for (const auto& w : j.at("warnings"))
    reason = reason || w.get<std::string>().find("not used; the advance is designed from the measured levels") !=
                           std::string::npos;
  CHECK(reason);
}

TEST_CASE("calibrate on the physics liquefier: the whole-record model and the per-level fits agree") {
  const std::string dir = test::scratch_dir("calibrate_whole_record") + "/run";
  const auto cli =
      test::run_cli({"calibrate", "--machine", "sim", "--skip-axes", "--sim", "liquefier=physics", "--out", dir});
  INFO(cli.err);
  REQUIRE(cli.code == 0);
  const auto env = nlohmann::json::parse(read_file_bytes(dir + "/results.json"));
  const auto step = nlohmann::json::parse(read_file_bytes(dir + "/analysis/step.json")).at("results");
  const auto& wr = step.at("whole_record");
  REQUIRE(wr.contains("a"));
  CHECK(wr.at("sensor") == "pressure");
  const double b = wr.at("b").at("value").get<double>();
  const auto truth = nlohmann::json::parse(read_file_bytes(dir + "/liquefier-step/truth.json")).at("liquefier");
  const double n = truth.at("n_index").get<double>();
  INFO("b = " << b << " [" << wr.at("b").at("ci95")[0] << ", " << wr.at("b").at("ci95")[1] << "], truth " << n - 1);
  CHECK(b == Approx(n - 1).margin(0.05));
  // Every operating point's tau against the model's prediction for the steps arriving there (the
  // model's own response over each step fitted as the step was), within their combined 95 %; at
  // 95 % each, one level in eight may miss by chance.
  const auto& checks = wr.at("step_checks");
  int compared = 0, missed = 0;
  for (const auto& l : step.at("operating_points")) {
    if (!(l.at("u").get<double>() > 0)) continue;
    double pred = 0, pred_se = 0;
    int n_pred = 0;
    for (const auto& i : l.at("steps"))
      for (const auto& c : checks)
        if (c.at("step") == i) {
          pred += c.at("tau_model_s").get<double>();
          pred_se += c.at("tau_model_stderr_s").get<double>();
          ++n_pred;
        }
    if (n_pred == 0) continue;
    pred /= n_pred;
    pred_se /= n_pred;
    const double tau = l.at("tau_s").get<double>(), se = l.at("stderr").at("tau_s").get<double>();
    const bool agree = std::abs(tau - pred) <= 1.96 * std::hypot(se, pred_se);
    INFO("u " << l.at("u") << ": level tau " << tau << " +- " << se << ", model " << pred << " +- " << pred_se);
    CHECK((agree || missed == 0));
    missed += !agree;
    ++compared;
  }
  CHECK(compared >= 6);
  // The design came from the model.
  bool from_model = false;
  for (const auto& note : env.at("results").at("compensators").at("flow_advance").at("notes"))
    from_model = from_model || note.get<std::string>().find("whole-record model") != std::string::npos;
  CHECK(from_model);
}
