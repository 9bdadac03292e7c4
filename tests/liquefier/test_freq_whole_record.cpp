// `tunekit freq` fits the whole-record liquefier model beside its per-frequency results: on a
// chirp of commanded flow through the store (tau(q) = a q^b) its tau at the record's mean flow
// agrees with the frequency response's tau; a record that cannot carry the model (the feed of the
// synthetic chirp data set swings below zero) is reported as not fitted, and freq still succeeds.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "synth_store.hpp"
#include "test_support.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"

using namespace tunekit;

namespace {

// A hold at the mean flow, then a linear chirp of +-amp around it (0.05-3 Hz), through the store
// of synth_store.hpp's truth, sampled at 50 Hz with Gaussian noise of 1 % of the mean output.
std::string store_chirp_log(const test::StoreTruth& tr, double mean, double amp, const std::string& name) {
  const double rate = 50, hold = 5, sweep = 60, f0 = 0.05, f1 = 3;
  std::vector<double> t, u;
  for (int i = 0; i < static_cast<int>((hold + sweep) * rate); ++i) {
    const double ti = i / rate, s = ti - hold;
    t.push_back(ti);
    const double phase = 2 * std::numbers::pi * (f0 * s + 0.5 * (f1 - f0) / sweep * s * s);
    u.push_back(s < 0 ? mean : mean + amp * std::sin(phase));
  }
  const auto y = fitting::simulate_liquefier(t, u, tr.params(), tr.sensor, 8);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01 * mean);
  std::ostringstream os;
  os.precision(10);
  os << "time_s,flow_mm3_s,outflow_mm3_s\n";
  for (std::size_t i = 0; i < t.size(); ++i) os << t[i] << "," << u[i] << "," << y[i] + noise(rng) << "\n";
  return test::write_scratch(name, os.str());
}

}  // namespace

TEST_CASE("freq on a chirp through the store: whole_record in the JSON, its tau at the mean flow agrees with freq's") {
  const test::StoreTruth tr;
  const double mean = 8, amp = 1.5;
  const std::string log = store_chirp_log(tr, mean, amp, "freq_store_chirp.csv");

  // The command line: the model in the JSON as step puts it, with intervals.
  const auto r = test::run_cli({"freq", log, "--input", "flow_mm3_s", "--output", "outflow_mm3_s", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out).at("results");
  REQUIRE(res.contains("whole_record"));
  const auto& wr = res.at("whole_record");
  for (const char* k : {"a", "b", "theta_s", "tau_ref_s"}) {
    INFO(k);
    REQUIRE(wr.contains(k));
    const double v = wr.at(k).at("value").get<double>();
    const auto& ci = wr.at(k).at("ci95");
    if (wr.at("linear_chosen").get<bool>() && std::string(k) == "b") continue;  // fixed at 0: no interval
    CHECK(ci[0].get<double>() <= v);
    CHECK(v <= ci[1].get<double>());
    CHECK(ci[0].get<double>() < ci[1].get<double>());
  }
  CHECK(wr.at("sensor") == "flow");
  INFO("theta " << wr.at("theta_s").at("value") << " s, truth " << tr.theta_s);
  CHECK(wr.at("theta_s").at("value").get<double>() == Approx(tr.theta_s).epsilon(0.2));

  // The library: the same fit, and its tau where the frequency response linearises the store.
  calibration::FreqOptions o;
  o.file = log;
  o.input_column = "flow_mm3_s";
  o.output_column = "outflow_mm3_s";
  const auto out = calibration::compute_freq(o);
  REQUIRE(out.whole_record.model);
  REQUIRE(out.reported_fit() != nullptr);
  const auto& m = *out.whole_record.model;
  const auto& ft = out.reported_fit()->param("tau_s");
  const double q = out.input_mean;
  CHECK(q == Approx(mean).epsilon(0.01));
  const double tau_m = m.tau_at(q), se_m = m.tau_stderr_at(q);
  INFO("model tau(" << q << ") = " << tau_m << " +- " << se_m << " s; freq tau " << ft.value << " +- " << ft.std_error
                    << " s; truth " << tr.tau(q) << " s");
  CHECK(std::abs(tau_m - ft.value) <= 1.96 * std::hypot(se_m, ft.std_error));
  // Both near the truth at the mean flow: the chirp's +-19 % swing keeps the store near linear.
  CHECK(tau_m == Approx(tr.tau(q)).epsilon(0.1));
  CHECK(ft.value == Approx(tr.tau(q)).epsilon(0.1));
  // The JSON's model is the library's.
  CHECK(wr.at("a").at("value").get<double>() == Approx(m.model.fit.derived.front().value).epsilon(1e-9));

  // The terminal: the model's line beside the output-error fit, with its tau at the mean flow.
  const auto text = test::run_cli({"freq", log, "--input", "flow_mm3_s", "--output", "outflow_mm3_s"});
  REQUIRE(text.code == 0);
  CHECK(text.out.find("output-error fit") != std::string::npos);
  CHECK(text.out.find("whole record: tau = a u^b") != std::string::npos);
  CHECK(text.out.find("its tau at the record's mean input") != std::string::npos);
}

TEST_CASE("freq on the synthetic chirp data set: the model is not fitted, with a plain reason, and freq succeeds") {
  const std::string csv = test::dataset("liquefier/synthetic_chirp.csv");
  const auto r = test::run_cli({"freq", csv, "--time", "time", "--input", "feed", "--output", "force", "--mode", "oe",
                                "--fit-tf", "2,0", "--fmax", "40", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto env = nlohmann::json::parse(r.out);
  const auto& res = env.at("results");
  // freq's own results stand.
  CHECK(res.at("fit").at("source") == "tf_oe_fit");
  REQUIRE(res.contains("whole_record"));
  REQUIRE(res.at("whole_record").contains("error"));
  const std::string why = res.at("whole_record").at("error").get<std::string>();
  INFO(why);
  CHECK(!why.empty());
  CHECK(why.find("tunekit") == std::string::npos);
  CHECK(!res.at("whole_record").contains("a"));
  bool warned = false;
  for (const auto& w : env.at("warnings"))
    warned = warned || w.get<std::string>() == "whole-record model not fitted: " + why;
  CHECK(warned);

  const auto text = test::run_cli(
      {"freq", csv, "--time", "time", "--input", "feed", "--output", "force", "--mode", "oe", "--fit-tf", "2,0"});
  REQUIRE(text.code == 0);
  CHECK(text.out.find("  whole record: not fitted: " + why + "\n") != std::string::npos);
  CHECK(text.err.find("warning: whole-record model not fitted") != std::string::npos);
}

TEST_CASE("freq's sine dwell without an input column says the model needs one, and succeeds") {
  const std::string csv = test::dataset("liquefier/appendix_d/exp_07.csv");
  const auto r =
      test::run_cli({"freq", csv, "--time", "time", "--output", "width", "--freq-hz", "0.05305165", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out).at("results");
  CHECK(res.contains("sine_dwell"));
  CHECK(res.at("whole_record").at("error").get<std::string>().find("no input column") != std::string::npos);
}
