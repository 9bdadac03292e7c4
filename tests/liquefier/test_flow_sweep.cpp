// The flow sweep: steps grouped by the level they arrive at, rising against falling, the level
// trends, the pooled-fit whiteness warning, and the liquefier-flow-sweep protocol's plan.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>

#include <nlohmann/json.hpp>

#include "synth_flow_sweep.hpp"
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/step_analysis.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/builtin_profile.hpp"

using namespace tunekit;

namespace {

ident::StepAnalysis analyze(const test::SynthFlowSweep& s) {
  ident::StepAnalysisOptions o;  // the default step detection finds every step of a sweep
  o.input_unit = "mm^3/s";
  return ident::analyze_steps(s.t, s.u, s.y, o);
}

}  // namespace

TEST_CASE(
    "a synthetic flow sweep with tau = a Q^b at each arrival level gives each level's tau within 2 % and b within "
    "0.05") {
  test::SynthFlowSweepTruth tr;
  const auto s = test::synth_flow_sweep(tr, 6, 1.5, 15, 5.0, 3.0);
  const auto a = analyze(s);
  // 6 measured levels and the two turning levels; 14 steps.
  REQUIRE(a.steps.size() == 14);
  REQUIRE(a.arrival_levels.size() == 8);
  int both = 0, differ = 0;
  for (const auto& l : a.arrival_levels) {
    INFO("level " << l.u << " tau " << l.fit.value("tau_s") << " truth " << tr.tau(l.u) << " r-f "
                  << l.rising_minus_falling_tau_s << " [" << l.rmf_ci95_lo << ", " << l.rmf_ci95_hi << "]");
    CHECK(l.fit.value("tau_s") == Approx(tr.tau(l.u)).epsilon(0.02));
    CHECK(l.fit.value("K") == Approx(tr.K).epsilon(0.02));
    CHECK(l.fit.value("theta_s") == Approx(tr.theta_s).margin(0.005));
    // The interval holds the truth.
    CHECK(l.fit.param("tau_s").ci95_lo <= tr.tau(l.u) * 1.0001);
    CHECK(tr.tau(l.u) * 0.9999 <= l.fit.param("tau_s").ci95_hi);
    if (l.n_rising == 1 && l.n_falling == 1) {
      ++both;
      // Rising and falling arrivals share the truth: their difference is a fraction of a per
      // cent of tau, measured to within 0.5 % (its 95 % interval holds 0 at most levels; at
      // 95 % a level may exclude it by chance).
      CHECK(std::abs(l.rising_minus_falling_tau_s) < 0.005 * tr.tau(l.u));
      CHECK(l.rmf_ci95_hi - l.rmf_ci95_lo < 0.01 * tr.tau(l.u));
      differ += l.directions_differ() ? 1 : 0;
    }
  }
  CHECK(both == 6);
  CHECK(differ <= 2);
  for (const double q : s.measured_flows) {
    const auto it = std::find_if(a.arrival_levels.begin(), a.arrival_levels.end(),
                                 [&](const auto& l) { return std::abs(l.u - q) < 1e-6 * q; });
    REQUIRE(it != a.arrival_levels.end());
    CHECK(it->n_rising == 1);
    CHECK(it->n_falling == 1);
  }
  REQUIRE(a.level_trends.tau);
  CHECK(a.level_trends.both_directions_only);
  CHECK(a.level_trends.tau->value("b") == Approx(tr.b).margin(0.05));
  CHECK(a.level_trends.tau->value("a") == Approx(tr.a).epsilon(0.05));
  const auto& b = a.level_trends.tau->param("b");
  CHECK(b.ci95_lo <= tr.b);
  CHECK(tr.b <= b.ci95_hi);
  REQUIRE(a.level_trends.K);
  CHECK(a.level_trends.K->value("b") == Approx(0).margin(0.02));
  REQUIRE(a.level_trends.theta);
  CHECK(a.level_trends.theta->value("c1") == Approx(0).margin(0.002));
  // The steps do not share one tau: the pooled fit over all of them is not white while the
  // single-step fits are, and the analysis says so.
  REQUIRE(a.pooled);
  CHECK(a.pooled->diagnostics.whiteness_p < ident::kWhitenessAlarmP);
  bool warned = false;
  for (const auto& w : a.warnings)
    warned = warned || w.find("pooled fit over all steps: its residuals are not white") == 0;
  CHECK(warned);
}

TEST_CASE("flow levels: rising and falling arrivals that differ are reported with an interval excluding zero") {
  // Falling arrivals 30 % slower than rising ones at the same level: a liquefier that is not first order.
  test::SynthFlowSweepTruth tr;
  tr.noise = 0.001;
  auto s = test::synth_flow_sweep(tr, 5, 2, 12, 5.0, 3.0);
  // Rebuild the output with the falling steps' tau scaled by 1.3.
  const auto plan = protocols::plan_flow_sweep(2, 12, 5, 1, 5.0, 1.0, 3.0);
  for (std::size_t i = 0; i < s.t.size(); ++i) {
    double y = tr.y0 + tr.K * plan.sequence_mm3_s.front();
    for (std::size_t k = 1; k < plan.sequence_mm3_s.size(); ++k) {
      const double q0 = plan.sequence_mm3_s[k - 1], q1 = plan.sequence_mm3_s[k];
      const double age = s.t[i] - (3.0 + static_cast<double>(k - 1) * 5.0) - tr.theta_s;
      const double tau = tr.tau(q1) * (q1 < q0 ? 1.3 : 1.0);
      if (age > 0) y += tr.K * (q1 - q0) * (1 - std::exp(-age / tau));
    }
    s.y[i] = y + tr.noise * std::sin(17.0 * static_cast<double>(i));  // deterministic small disturbance
  }
  const auto a = analyze(s);
  int differ = 0;
  for (const auto& l : a.arrival_levels) {
    if (l.n_rising == 0 || l.n_falling == 0) continue;
    INFO("level " << l.u << " rising - falling " << l.rising_minus_falling_tau_s);
    CHECK(l.rising_minus_falling_tau_s == Approx(-0.3 * tr.tau(l.u)).epsilon(0.1));
    CHECK(l.rmf_ci95_hi < 0);
    differ += l.directions_differ() ? 1 : 0;
  }
  CHECK(differ == 5);
  const auto j = ident::to_json(a);
  REQUIRE(j.at("operating_points").size() == 7);
  const auto& lv = j.at("operating_points")[1];
  CHECK(lv.at("unit") == "mm^3/s");
  CHECK(lv.at("n_rising") == 1);
  CHECK(lv.at("n_falling") == 1);
  CHECK(lv.at("directions_differ") == true);
  CHECK(lv.at("rising_minus_falling_tau_ci95").size() == 2);
  CHECK(lv.at("tau_ci95").size() == 2);
  CHECK(j.at("trend").at("tau_s").at("b_ci95").size() == 2);
  CHECK(j.at("trend").contains("K"));
  CHECK(j.at("trend").contains("theta_s"));
}

TEST_CASE("the pooled-fit whiteness warning needs white single-step fits that differ beyond the margin") {
  auto fit = [](double p, double tau, double tau_se) {
    fitting::FitResult f;
    f.diagnostics.whiteness_p = p;
    fitting::Param k, t;
    k.name = "K";
    k.value = 3.5;
    k.std_error = 0.001;
    t.name = "tau_s";
    t.value = tau;
    t.std_error = tau_se;
    f.params = {k, t};
    return f;
  };
  // One step's tau 11 % above the pooled value, known to 0.5 %: beyond tau's 2 % margin.
  const fitting::FitResult pooled = fit(1e-6, 0.45, 0.001), white = fit(0.4, 0.5, 0.0025),
                           coloured = fit(1e-5, 0.5, 0.0025);
  CHECK_FALSE(ident::pooled_whiteness_warning(pooled, {&white, &white, &white, &white}, "pooled").empty());
  // The steps differ from the pooled fit by 0.4 %, far beyond their noise but within the
  // margin: one K and tau describe them for any compensator, and nothing is said.
  const fitting::FitResult close = fit(0.4, 0.4518, 0.0002);
  CHECK(ident::pooled_whiteness_warning(pooled, {&close, &close, &close, &close}, "pooled").empty());
  // Most single-step fits are not white either: the pooled fit says nothing new.
  CHECK(ident::pooled_whiteness_warning(pooled, {&white, &coloured, &coloured, &coloured}, "pooled").empty());
  // A white pooled fit is no warning.
  CHECK(ident::pooled_whiteness_warning(white, {&white, &white}, "pooled").empty());
}

TEST_CASE("liquefier-flow-sweep reaches every level from below and above, within the profile's flow limit") {
  const auto profile = sim::builtin_sim_profile();
  using firmware::Firmware;
  for (const auto fw : {Firmware::marlin, Firmware::klipper, Firmware::reprapfirmware}) {
    INFO(firmware::to_string(fw));
    const firmware::Dialect dialect(fw);
    const auto e = protocols::build_experiment("liquefier-flow-sweep", {}, "", profile, dialect);
    const auto& flows = e.excitation.at("measured_flows_mm3_s");
    REQUIRE(flows.size() == 6);
    CHECK(e.excitation.at("turning_flows_mm3_s")[1].get<double>() == Approx(0.9 * profile.extruder.max_flow_mm3_s));
    CHECK(e.excitation.at("turning_flows_mm3_s")[0].get<double>() == Approx(0.09 * profile.extruder.max_flow_mm3_s));
    // Hold: 6 expected time constants at the lowest flow; 14 steps after the settle.
    CHECK(e.excitation.at("hold_s").get<double>() == Approx(3.0));
    CHECK(e.estimated_duration_s >= 3.0 + 14 * 3.0 - 0.5);
    CHECK(protocols::check_protocol(e.gcode, profile, e.sensors).empty());
    // The extrude-only acceleration is set as the firmware wants it.
    const std::string all = [&] {
      std::string s;
      for (const auto& l : e.gcode) s += l + "\n";
      return s;
    }();
    if (fw == Firmware::klipper) CHECK(all.find("SET_VELOCITY_LIMIT ACCEL=") != std::string::npos);
    if (fw == Firmware::marlin) CHECK(all.find("M204 R") != std::string::npos);
    if (fw == Firmware::reprapfirmware) CHECK(all.find("M201 E") != std::string::npos);
  }
  const auto plan = protocols::plan_flow_sweep(1, 10, 5, 2, 0.5, 6, 3);
  CHECK(plan.steps() == 2 * 2 * 6);
  CHECK(plan.ratio == Approx(std::pow(10.0, 1.0 / 6)));
  CHECK(plan.sequence_mm3_s.front() == 1);
  CHECK(plan.sequence_mm3_s[6] == Approx(10));
  CHECK_THROWS_AS(protocols::plan_flow_sweep(5, 5, 6, 1, 0.5, 6, 3), InputError);
  // A flow above the hot end's limit is refused by the safety gate.
  const auto e = protocols::build_experiment("liquefier-flow-sweep", {{"flow_max_mm3_s", 40}}, "", profile,
                                             firmware::Dialect(firmware::Firmware::marlin));
  CHECK_FALSE(protocols::check_protocol(e.gcode, profile, e.sensors).empty());
}

namespace {

// The synthetic sweep as a log `tunekit step` reads: time, flow (mm^3/s) and force (N).
std::string sweep_log(const test::SynthFlowSweep& s, const std::string& name) {
  std::ostringstream os;
  os << "time_s,flow_mm3_s,force_N\n";
  for (std::size_t i = 0; i < s.t.size(); ++i) os << s.t[i] << "," << s.u[i] << "," << s.y[i] << "\n";
  return test::write_scratch(name, os.str());
}

// The exponent b of tau = a Q^b through the first and last points of export's tau(Q) curve.
double curve_exponent(const nlohmann::json& curve) {
  const auto &c0 = curve.front(), &c1 = curve.back();
  return std::log(c1.at("tau_s").get<double>() / c0.at("tau_s").get<double>()) /
         std::log(c1.at("flow_mm3_s").get<double>() / c0.at("flow_mm3_s").get<double>());
}

}  // namespace

TEST_CASE("tunekit step and export with their defaults on a flow sweep with tau = a Q^-0.45 at the arrival level") {
  test::SynthFlowSweepTruth tr;
  tr.b = -0.45;
  // 2 to 12 mm^3/s: export's default design flow (a 0.45 x 0.2 mm line at 60 mm/s, 5.4 mm^3/s)
  // lies inside the levels the log reaches.
  const auto s = test::synth_flow_sweep(tr, 5, 2, 12, 5.0, 3.0);
  const std::string log = sweep_log(s, "sweep_b045.csv");
  const std::string dir = test::scratch_dir("sweep_b045");
  const auto r =
      test::run_cli({"step", log, "--input", "flow_mm3_s", "--output", "force_N", "--json", "-o", dir + "/step.json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto res = nlohmann::json::parse(r.out).at("results");
  CHECK(res.at("steps").size() == 12);
  REQUIRE(res.at("operating_points").size() == 7);
  CHECK(res.at("trend").at("tau_s").at("b").get<double>() == Approx(tr.b).margin(0.05));
  // Every exponent the text prints (u^B) is the truth's.
  const auto text = test::run_cli({"step", log, "--input", "flow_mm3_s", "--output", "force_N"});
  REQUIRE(text.code == 0);
  int printed = 0;
  for (std::size_t at = text.out.find("tau_s = "); at != std::string::npos; at = text.out.find("tau_s = ", at + 1)) {
    const auto caret = text.out.find("u^", at);
    REQUIRE(caret != std::string::npos);
    INFO(text.out.substr(at, 60));
    CHECK(std::stod(text.out.substr(caret + 2)) == Approx(tr.b).margin(0.05));
    ++printed;
  }
  CHECK(printed >= 1);

  // Export designs from the operating points: the levels the log reached (2 to 12 mm^3/s).
  std::filesystem::copy_file(test::dataset("firmware/printer.cfg"), dir + "/printer.cfg",
                             std::filesystem::copy_options::overwrite_existing);
  const auto e = test::run_cli({"export", "-f", "klipper", "-c", dir + "/printer.cfg", dir + "/step.json", "--json"});
  INFO(e.err);
  REQUIRE(e.code == 0);
  const auto ej = nlohmann::json::parse(e.out);
  for (const auto& w : ej.at("warnings"))
    CHECK(w.get<std::string>().find("outside the identified") == std::string::npos);
  const auto& fa = ej.at("results").at("flow_advance");
  REQUIRE(fa.is_object());
  CHECK(fa.at("flow_range_mm3_s")[0].get<double>() == Approx(2).epsilon(0.02));
  CHECK(fa.at("flow_range_mm3_s")[1].get<double>() == Approx(12).epsilon(0.02));
  CHECK(curve_exponent(fa.at("curve")) == Approx(tr.b).margin(0.05));
  CHECK(ej.at("results").at("design").at("schedule").size() == 7);
}
