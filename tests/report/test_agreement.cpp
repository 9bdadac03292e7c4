// Agreement of a quantity measured two ways, and when a liquefier gain is compared with 1.
#include <catch2/catch.hpp>

#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/calibration/results/warning_advice.hpp"
#include <filesystem>
#include <nlohmann/json.hpp>
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/pressure_advance.hpp"

using namespace tunekit::calibration;

TEST_CASE("two estimates do NOT agree only when the interval of their difference lies beyond the margin") {
  const auto margin = tunekit::fitting::equivalence_margin("tau_s");
  REQUIRE(margin.relative == Approx(0.02));
  const Estimate step{"step response", 0.45, 0.44, 0.46};
  // 9 % apart, half-widths 0.01 and 0.01 (combined 0.0141): the difference's interval
  // [0.026, 0.054] s lies beyond the 2 % margin (0.0094 s).
  const auto bad = compare_estimates("tau", "s", step, {"frequency response", 0.49, 0.48, 0.50}, margin);
  CHECK(bad.verdict == "differ");
  CHECK_FALSE(bad.agree);
  CHECK(bad.combined_half_width == Approx(std::sqrt(2.0) * 0.01));
  CHECK(bad.margin_value == Approx(0.02 * 0.47));
  CHECK(bad.statement.find("do NOT agree") != std::string::npos);
  CHECK(advice_for_warning(bad.statement).find("repeat both experiments") == 0);
  // As results JSON holds it.
  const auto j = to_json(bad);
  CHECK(j.at("verdict") == "differ");
  CHECK_FALSE(j.at("agree").get<bool>());
  CHECK(j.at("margin").at("value").get<double>() == bad.margin_value);
  CHECK(j.at("estimates")[1].at("ci95")[0].get<double>() == 0.48);
  CHECK_FALSE(j.contains("id"));
  // 0.25 % apart with intervals far narrower than that: different, but not by a margin a
  // compensator feels: equivalent (the old test of equality called this a disagreement).
  const auto close = compare_estimates("tau", "s", {"step response", 0.4497, 0.4496, 0.4498},
                                       {"frequency response", 0.4508, 0.4507, 0.4509}, margin);
  CHECK(close.verdict == "equivalent");
  CHECK(close.agree);
  CHECK(close.statement.find("NOT") == std::string::npos);
  // Wide intervals: not shown to differ, not shown equivalent; no disagreement either.
  const auto wide = compare_estimates("tau", "s", {"step response", 0.45, 0.42, 0.48},
                                      {"frequency response", 0.49, 0.45, 0.53}, margin);
  CHECK(wide.verdict == "undecided");
  CHECK(wide.agree);
  CHECK(wide.statement.find("NOT") == std::string::npos);
}

TEST_CASE("an estimate whose interval does not hold its value is refused") {
  CHECK_THROWS_AS(compare_estimates("tau", "s", {"a", 0.5, 0.6, 0.7}, {"b", 0.5, 0.4, 0.6}, {}), tunekit::InputError);
  CHECK_THROWS_AS(compare_estimates("tau", "s", {"a", std::nan(""), 0.4, 0.6}, {"b", 0.5, 0.4, 0.6}, {}),
                  tunekit::InputError);
}

TEST_CASE("the liquefier gain is compared with 1 only when input and output share units") {
  using tunekit::design::gain_is_dimensionless;
  CHECK(gain_is_dimensionless("1"));
  CHECK(gain_is_dimensionless("mm/(mm)"));
  CHECK(gain_is_dimensionless("mm/mm"));
  CHECK(gain_is_dimensionless("mm^3/s/(mm^3/s)"));
  CHECK_FALSE(gain_is_dimensionless("N/(mm/s)"));
  CHECK_FALSE(gain_is_dimensionless(""));
  tunekit::design::AdvanceInputs in;
  in.tau_s = 0.45;
  in.gain = 3.5;
  in.filament_area_mm2 = 2.405;
  in.line_area_mm2 = 0.09;
  in.print_speed_mm_s = 60;
  in.print_accel_mm_s2 = 3000;
  in.extruder_accel_limit_mm_s2 = 5000;
  auto gain_warned = [](const tunekit::design::AdvanceDesign& d) {
    for (const auto& w : d.warnings)
      if (w.find("differs from 1") != std::string::npos) return true;
    return false;
  };
  in.gain_unit = "N/(mm/s)";  // feed in, force out: no natural 1
  CHECK_FALSE(gain_warned(tunekit::design::design_advance(in)));
  in.gain_unit = "mm/(mm)";  // width in, width out
  CHECK(gain_warned(tunekit::design::design_advance(in)));
}

TEST_CASE("export compares the step and frequency-response taus by the margin rule, not by their gap") {
  auto envelope = [](const std::string& command, const nlohmann::json& tau) {
    nlohmann::json params{{"tau_s", tau}};
    nlohmann::json results = command == "step" ? nlohmann::json{{"pooled", {{"params", params}}}}
                                               : nlohmann::json{{"fit", {{"source", "tf_oe_fit"}, {"params", params}}}};
    return nlohmann::json{{"command", command}, {"schema_version", 1}, {"results", results}}.dump();
  };
  auto tau = [](double v, double lo, double hi) {
    return nlohmann::json{{"value", v}, {"stderr", (hi - lo) / 3.92}, {"ci95", {lo, hi}}, {"unit", "s"}};
  };
  const std::string cfg = tunekit::test::scratch_dir("agreement_export") + "/printer.cfg";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/printer.cfg"), cfg,
                             std::filesystem::copy_options::overwrite_existing);
  const std::string step = tunekit::test::write_scratch("agree_step.json", envelope("step", tau(0.45, 0.44, 0.46)));
  auto run = [&](const std::string& freq_file) {
    const auto r = tunekit::test::run_cli({"export", "-f", "klipper", "-c", cfg, step, freq_file, "--json"});
    INFO(r.err);
    REQUIRE(r.code == 0);
    return nlohmann::json::parse(r.out);
  };
  auto warned = [](const nlohmann::json& env) {
    for (const auto& w : env.at("warnings"))
      if (w.get<std::string>().find("liquefier time constant tau") != std::string::npos) return true;
    return false;
  };
  // 9 % apart, each interval narrow: the difference is beyond the 2 % margin, and export says so.
  const auto close = run(tunekit::test::write_scratch("agree_close.json", envelope("freq", tau(0.49, 0.48, 0.50))));
  REQUIRE(close.at("results").at("agreement").size() == 1);
  CHECK_FALSE(close.at("results").at("agreement")[0].at("agree").get<bool>());
  CHECK(warned(close));
  // 25 % apart, but the frequency response's interval is wide: they agree, and nothing is said.
  const auto wide = run(tunekit::test::write_scratch("agree_wide.json", envelope("freq", tau(0.6, 0.3, 0.9))));
  CHECK(wide.at("results").at("agreement")[0].at("agree").get<bool>());
  CHECK_FALSE(warned(wide));
  // The design uses the step's tau either way.
  CHECK(wide.at("results").at("design").at("K_s").get<double>() == 0.45);
}
