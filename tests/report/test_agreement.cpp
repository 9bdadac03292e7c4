// Agreement of a quantity measured two ways, and when a liquefier gain is compared with 1.
#include <catch2/catch.hpp>

#include "tunekit/calibration/agreement.hpp"
#include "tunekit/calibration/warning_advice.hpp"
#include <filesystem>
#include <nlohmann/json.hpp>
#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/pressure_advance.hpp"

using namespace tunekit::calibration;

TEST_CASE("two estimates agree when their difference is within the combined 95 % half-width") {
  // Half-widths 0.03 and 0.04 combine to 0.05.
  const Estimate step{"step response", 0.45, 0.42, 0.48};
  const auto ok = compare_estimates("tau", "s", step, {"frequency response", 0.49, 0.45, 0.53});
  CHECK(ok.at("agree").get<bool>());
  CHECK(ok.at("combined_half_width").get<double>() == Approx(0.05));
  CHECK(ok.at("statement").get<std::string>().find("agree within their combined 95 % uncertainty") !=
        std::string::npos);
  const auto bad = compare_estimates("tau", "s", step, {"frequency response", 0.51, 0.47, 0.55});
  CHECK_FALSE(bad.at("agree").get<bool>());
  CHECK(bad.at("statement").get<std::string>().find("do NOT agree") != std::string::npos);
  CHECK(advice_for_warning(bad.at("statement").get<std::string>()).find("repeat both experiments") == 0);
}

TEST_CASE("an estimate whose interval does not hold its value is refused") {
  CHECK_THROWS_AS(compare_estimates("tau", "s", {"a", 0.5, 0.6, 0.7}, {"b", 0.5, 0.4, 0.6}), tunekit::InputError);
  CHECK_THROWS_AS(compare_estimates("tau", "s", {"a", std::nan(""), 0.4, 0.6}, {"b", 0.5, 0.4, 0.6}),
                  tunekit::InputError);
}

TEST_CASE("the liquefier gain is compared with 1 only when input and output share units") {
  using tunekit::ident::gain_is_dimensionless;
  CHECK(gain_is_dimensionless("1"));
  CHECK(gain_is_dimensionless("mm/(mm)"));
  CHECK(gain_is_dimensionless("mm/mm"));
  CHECK(gain_is_dimensionless("mm^3/s/(mm^3/s)"));
  CHECK_FALSE(gain_is_dimensionless("N/(mm/s)"));
  CHECK_FALSE(gain_is_dimensionless(""));
  tunekit::ident::AdvanceInputs in;
  in.tau_s = 0.45;
  in.gain = 3.5;
  in.filament_area_mm2 = 2.405;
  in.line_area_mm2 = 0.09;
  in.print_speed_mm_s = 60;
  in.print_accel_mm_s2 = 3000;
  in.extruder_accel_limit_mm_s2 = 5000;
  auto gain_warned = [](const tunekit::ident::AdvanceDesign& d) {
    for (const auto& w : d.warnings)
      if (w.find("differs from 1") != std::string::npos) return true;
    return false;
  };
  in.gain_unit = "N/(mm/s)";  // feed in, force out: no natural 1
  CHECK_FALSE(gain_warned(tunekit::ident::design_advance(in)));
  in.gain_unit = "mm/(mm)";  // width in, width out
  CHECK(gain_warned(tunekit::ident::design_advance(in)));
}

TEST_CASE("export compares the step and frequency-response taus by the combined-interval rule, not by their gap") {
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
  // 4 % apart, but each interval is narrow: they do not agree, and export says so.
  const auto close = run(tunekit::test::write_scratch("agree_close.json", envelope("freq", tau(0.47, 0.46, 0.48))));
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
