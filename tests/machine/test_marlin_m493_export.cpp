// The exported runtime G-code of a Marlin running fixed-time motion, in the M493 letters of the
// form its report took (Marlin/src/gcode/feature/ft_motion/M493.cpp, 2023 to late 2025): the
// lines each form's letters give, and the simulated build of that form taking them.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/marlin_m493.hpp"
#include "tunekit/sim/simulator.hpp"
#include "sim_m493_answers.hpp"

using namespace tunekit::firmware;
using tunekit::sim::SimConfig;
using tunekit::sim::Simulator;

namespace {

/// X MZV at 45.2 Hz, Y `y_type` at 38 Hz, K 0.045, exported for a live Marlin of `form`.
ExportResult export_for(const std::string& form, const std::string& y_type = "zv") {
  CompensatorSettings s;
  s.pa_k_s = 0.045;
  s.shapers["x"] = {"mzv", 45.2, 0.1};
  s.shapers["y"] = {y_type, 38, 0.08};
  s.marlin_ft_motion_live = true;
  s.marlin_m493 = parse_m493_syntax(form);
  const std::string cfg = tunekit::read_file_bytes(std::string(TUNEKIT_DATASETS_DIR) + "/firmware/Configuration_adv.h");
  return export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
}

bool warned(const ExportResult& r, const std::string& what) {
  for (const auto& w : r.warnings)
    if (w.find(what) != std::string::npos) return true;
  return false;
}

struct Expected {
  const char* form;
  const char* y_type;  // the 2023 form has one shaper for X and Y
  const char* y_name;  // as the report names it
  std::vector<std::string> gcode;
};

const std::vector<Expected>& expected_forms() {
  static const std::vector<Expected> forms = {
      {"mode", "mzv", "MZV", {"M493 S15 A45.2 B38", "M493 P1 K0.045", "M500"}},
      {"axis_slash", "zv", "ZV", {"M493 S1 X8 Y1 A45.2 B38 I0.1 J0.08", "M493 P1 K0.045", "M500"}},
      {"axis_named", "zv", "ZV", {"M493 S1 X8 Y1 A45.2 B38 I0.1 J0.08", "M493 P1 K0.045", "M500"}},
      {"axis_list", "zv", "ZV", {"M493 S1 X8 Y1 A45.2 B38 I0.1 J0.08", "M493 P1 K0.045", "M500"}},
      {"axis_list_v2", "zv", "ZV", {"M493 S1 X C8 A45.2 I0.1", "M493 Y C1 A38 I0.08", "M500"}}};
  return forms;
}

}  // namespace

TEST_CASE("the exported M493 G-code takes the letters of each report form, and says what a form cannot set",
          "[machine][export]") {
  for (const auto& e : expected_forms()) {
    INFO(e.form);
    const auto r = export_for(e.form, e.y_type);
    CHECK(tunekit::test::text_lines(r.gcode) == e.gcode);
    CHECK(r.gcode.find("M593") == std::string::npos);
    CHECK(r.gcode.find("M900") == std::string::npos);
    const std::string form = e.form;
    // 2023: no damping letter; late 2025 (FTM V2): no linear advance letter.
    CHECK(warned(r, "damping ratio") == (form == "mode"));
    CHECK(warned(r, "advance K 0.045") == (form == "axis_list_v2"));
  }
  // The 2023 form's one mode for X and Y: X's shaper, and a warning naming Y's.
  const auto mixed = export_for("mode", "zv");
  CHECK(tunekit::test::text_lines(mixed.gcode).front() == "M493 S15 A45.2 B38");
  CHECK(warned(mixed, "one mode for X and Y"));
  // A shaper that came after the 2023 form (ZVDD) is left out there, with a warning.
  CompensatorSettings s;
  s.shapers["x"] = {"zvdd", 50, 0.1};
  s.marlin_ft_motion_live = true;
  s.marlin_m493 = parse_m493_syntax("mode");
  const auto zvdd = export_config_text(ExportFirmware::marlin, "", "Configuration_adv.h", s);
  CHECK(zvdd.gcode.find("M493 S") == std::string::npos);
  CHECK(warned(zvdd, "ZVDD"));
  CHECK_THROWS_AS(parse_m493_syntax("axis_list_v3"), tunekit::InputError);
  for (const auto& e : expected_forms()) CHECK(to_string(parse_m493_syntax(e.form)) == e.form);
}

TEST_CASE("the simulated Marlin of each M493 form takes the exported G-code and shapes at its type and frequency",
          "[machine][export]") {
  for (const auto& e : expected_forms()) {
    INFO(e.form);
    // Start from other shapers and frequencies than the export's.
    Simulator sim(SimConfig::from_options({"firmware=marlin", "ft_motion=on", std::string("m493_form=") + e.form,
                                           "ft_shaper_x=1:30", "ft_shaper_y=1:31"}));
    for (const auto& line : tunekit::test::text_lines(export_for(e.form, e.y_type).gcode)) {
      INFO(line);
      for (const auto& answer : tunekit::test::sim_answer_lines(sim, line)) {
        CHECK(answer.find("Invalid") == std::string::npos);
        CHECK(answer.find("Wrong mode") == std::string::npos);
      }
    }
    const auto r = tunekit::test::ask_sim_m493(sim);
    CHECK(r.active);
    CHECK(to_string(m493_syntax(r)) == e.form);
    REQUIRE(r.axes.count("x"));
    REQUIRE(r.axes.count("y"));
    CHECK(r.axes.at("x").name == "MZV");
    CHECK(r.axes.at("x").freq_hz == Approx(45.2));
    CHECK(r.axes.at("y").name == e.y_name);
    CHECK(r.axes.at("y").freq_hz == Approx(38));
  }
}

TEST_CASE("tunekit export --marlin-m493-form writes that form's letters and refuses an unknown form",
          "[machine][cli]") {
  const std::string dir = tunekit::test::scratch_dir("m493_export_cli");
  const std::string cfg = std::string(TUNEKIT_DATASETS_DIR) + "/firmware/Configuration_adv.h";
  const std::vector<std::string> base = {
      "export", "--firmware", "marlin",       "--config",   cfg,          "--pa-k",
      "0.045",  "--shaper-x", "mzv:45.2:0.1", "--shaper-y", "zv:38:0.08", "--marlin-ft-motion"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return tunekit::test::run_cli(args);
  };
  const auto v2 = with({"--marlin-m493-form", "axis_list_v2", "--gcode", dir + "/v2.gcode"});
  INFO(v2.err);
  REQUIRE(v2.code == 0);
  CHECK(tunekit::test::read_text(dir + "/v2.gcode") == "M493 S1 X C8 A45.2 I0.1\nM493 Y C1 A38 I0.08\nM500\n");
  const auto plain = with({"--gcode", dir + "/default.gcode"});
  REQUIRE(plain.code == 0);
  CHECK(tunekit::test::read_text(dir + "/default.gcode") ==
        "M493 S1 X8 Y1 A45.2 B38 I0.1 J0.08\nM493 P1 K0.045\nM500\n");
  const auto bad = with({"--marlin-m493-form", "axis_list_v3"});
  CHECK(bad.code == 2);
  CHECK(bad.err.find("tunekit: error: --marlin-m493-form 'axis_list_v3'") != std::string::npos);
}

TEST_CASE("calibrate on a simulated Marlin running FT_MOTION exports the letters of its M493 form", "[machine][cli]") {
  for (const std::string form : {"mode", "axis_list_v2"}) {
    INFO(form);
    const std::string dir = tunekit::test::scratch_dir("calibrate_m493_" + form) + "/run";
    const auto cli =
        tunekit::test::run_cli({"calibrate", "--machine", "sim", "--firmware", "marlin", "--skip-liquefier", "--out",
                                dir, "--sim", "firmware=marlin", "--sim", "ft_motion=on", "--sim", "m493_form=" + form,
                                "--sim", "ft_shaper_x=1:40", "--sim", "ft_shaper_y=1:40"});
    INFO(cli.err);
    REQUIRE(cli.code == 0);
    const auto ex = nlohmann::json::parse(tunekit::read_file_bytes(dir + "/results.json"))
                        .at("results")
                        .at("compensators")
                        .at("export");
    const std::string gcode = ex.at("gcode").get<std::string>();
    INFO(gcode);
    const auto analysis = nlohmann::json::parse(tunekit::read_file_bytes(dir + "/analysis/export.json"));
    CHECK(analysis.at("results").at("settings").at("marlin_m493_form") == form);
    const auto lines = tunekit::test::text_lines(gcode);
    REQUIRE(lines.size() >= 2);
    if (form == "mode") {
      CHECK(lines.front().rfind("M493 S1", 0) == 0);  // S10 ZV .. S15 MZV
      CHECK(lines.front().find(" I") == std::string::npos);
    } else {
      CHECK(lines.at(0).rfind("M493 S1 X C", 0) == 0);
      CHECK(lines.at(1).rfind("M493 Y C", 0) == 0);
    }
    CHECK(gcode.find("M593") == std::string::npos);
  }
}
