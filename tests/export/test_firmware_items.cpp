// Marlin and RepRapFirmware details the export must respect, from the firmwares' source:
//   Marlin Configuration_adv.h: ADVANCE_K is a per-extruder list with DISTINCT_E_FACTORS;
//     Marlin/src/gcode/feature/advance/M900.cpp: with ADVANCE_K_EXTRA and slot 1 active, K goes to
//     the backup slot (S0 selects slot 0); T selects the extruder.
//   Marlin/src/gcode/feature/input_shaping/M593.cpp: seen_X is TERN0(INPUT_SHAPING_X, ...), so on
//     a Y-only build "M593 X F.." sets Y.
//   RepRapFirmware GCodes2.cpp case 572: "M572 D0:1 S0.2:0.3" gives each listed drive its value.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_export.hpp"

using namespace tunekit;
using namespace tunekit::firmware;

TEST_CASE("Marlin: a per-extruder ADVANCE_K list keeps the other extruders' values") {
  const std::string cfg = "#define LIN_ADVANCE\n  #define ADVANCE_K { 0.22, 0.30 }    // (mm) per extruder\n";
  CompensatorSettings s;
  s.pa_k_s = 0.045;
  s.extruder_index = 1;
  auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.updated == "#define LIN_ADVANCE\n  #define ADVANCE_K { 0.22, 0.045 }    // (mm) per extruder\n");
  CHECK(r.gcode.find("M900 T1 K0.045") != std::string::npos);
  s.extruder_index = 0;
  r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.updated == "#define LIN_ADVANCE\n  #define ADVANCE_K { 0.045, 0.30 }    // (mm) per extruder\n");
  s.extruder_index = 2;
  CHECK_THROWS_AS(export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s), InputError);
}

TEST_CASE("Marlin: with ADVANCE_K_EXTRA the M900 line selects slot 0 so K is the active value") {
  const std::string cfg = "#define LIN_ADVANCE\n#define ADVANCE_K 0.22\n#define ADVANCE_K_EXTRA\n";
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  const auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.gcode == "M900 S0 K0.05\nM500\n");
}

TEST_CASE("Marlin: on a Y-only shaping build no lone 'M593 X' is emitted (it would set Y)") {
  const std::string cfg =
      "//#define INPUT_SHAPING_X\n#define INPUT_SHAPING_Y\n#define SHAPING_FREQ_X 40\n#define SHAPING_ZETA_X 0.15f\n"
      "#define SHAPING_FREQ_Y 40\n#define SHAPING_ZETA_Y 0.15f\n";
  CompensatorSettings s;
  s.shapers["x"] = {"zv", 44, 0.1};
  s.shapers["y"] = {"zv", 41, 0.1};
  const auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.gcode.find("M593 X") == std::string::npos);
  CHECK(r.gcode.find("M593 Y F41 D0.1") != std::string::npos);
  CHECK(r.updated.find("\n#define INPUT_SHAPING_X\n") == std::string::npos);  // first line, no leading \n
  CHECK(r.updated.rfind("#define INPUT_SHAPING_X\n", 0) == 0);
  REQUIRE_FALSE(r.warnings.empty());
  CHECK(r.warnings.back().find("INPUT_SHAPING_X") != std::string::npos);
}

TEST_CASE("RepRapFirmware: M572 with a drive list sets only the chosen drive's value") {
  CompensatorSettings s;
  s.pa_k_s = 0.07;
  s.rrf_drive = 1;
  auto r = export_config_text(ExportFirmware::rrf, "M584 E3:4\nM572 D0:1 S0.2:0.3\n", "config.g", s);
  CHECK(r.updated == "M584 E3:4\nM572 D0:1 S0.2:0.07\n");
  r = export_config_text(ExportFirmware::rrf, "M584 E3:4\nM572 D0:1 S0.2\n", "config.g", s);
  CHECK(r.updated == "M584 E3:4\nM572 D0:1 S0.2:0.07\n");
  CHECK(r.gcode.find("M572 D1 S0.07") != std::string::npos);
}

TEST_CASE("Marlin FT_MOTION: shapers and K go to the FT_MOTION defaults, not the bypassed classic ones") {
  // Marlin Configuration_adv.h FT_MOTION block (FTM_DEFAULT_SHAPER_X ftMotionShaper_<type>,
  // FTM_SHAPING_DEFAULT_FREQ_X, FTM_SHAPING_ZETA_X; types from ft_types.h); stepper.cpp isr():
  // with FT motion active the classic shaper and SMOOTH_LIN_ADVANCE are bypassed.
  const std::string cfg =
      "#define LIN_ADVANCE\n#define ADVANCE_K 0.22\n"
      "#define INPUT_SHAPING_X\n#define SHAPING_FREQ_X 40\n#define SHAPING_ZETA_X 0.15f\n"
      "#define FT_MOTION\n#if ENABLED(FT_MOTION)\n"
      "  #define FTM_DEFAULT_SHAPER_X      ftMotionShaper_NONE // (NONE, ZV, ZVD, ...)\n"
      "  #define FTM_SHAPING_DEFAULT_FREQ_X   37.0f    // (Hz)\n"
      "  #define FTM_SHAPING_ZETA_X            0.1f    // zeta\n"
      "#endif\n";
  CHECK(marlin_ft_motion_enabled(cfg));
  CHECK_FALSE(marlin_ft_motion_enabled("//#define FT_MOTION\n#define FT_MOTION_MENU\n"));
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  s.pa_smooth_s = 0.01;
  s.shapers["x"] = {"mzv", 45, 0.12};  // classic Marlin is ZV only; FT_MOTION has MZV
  const auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.updated ==
        "#define LIN_ADVANCE\n#define ADVANCE_K 0.05\n"
        "#define INPUT_SHAPING_X\n#define SHAPING_FREQ_X 40\n#define SHAPING_ZETA_X 0.15f\n"
        "#define FT_MOTION\n#if ENABLED(FT_MOTION)\n"
        "  #define FTM_DEFAULT_SHAPER_X      ftMotionShaper_MZV // (NONE, ZV, ZVD, ...)\n"
        "  #define FTM_SHAPING_DEFAULT_FREQ_X   45.0f    // (Hz)\n"
        "  #define FTM_SHAPING_ZETA_X            0.12f   // zeta\n"
        "#endif\n");
  CHECK(r.gcode.find("M593") == std::string::npos);
  bool tau_warning = false;
  for (const auto& w : r.warnings) tau_warning |= w.find("SMOOTH_LIN_ADVANCE") != std::string::npos;
  CHECK(tau_warning);
  s.shapers["x"] = {"mzv", 45, 0.12};
  CHECK_THROWS_AS(export_config_text(ExportFirmware::marlin, "#define INPUT_SHAPING_X\n", "c.h", s), InputError);
}

TEST_CASE("export takes the best-scoring candidate the firmware has when the recommendation is not available") {
  // Marlin's classic input shaping is ZV only (M593.cpp); RepRapFirmware has no zv and no ei
  // (AxisShaper.h). The shaper results list every type's best frequency with its score.
  const std::string results = tunekit::test::write_scratch("shaper_candidates.json", R"({
  "command": "shaper", "schema_version": 1,
  "results": {"axes": {"x": {
    "recommended": {"type": "ei", "freq_hz": 52.4, "damping": 0.1, "score": 0.010},
    "candidates": [
      {"type": "zv", "freq_hz": 44.2, "damping": 0.1, "score": 0.030},
      {"type": "mzv", "freq_hz": 49.0, "damping": 0.1, "score": 0.020},
      {"type": "ei", "freq_hz": 52.4, "damping": 0.1, "score": 0.010}]}}}})");
  const std::string cfg = tunekit::test::write_scratch(
      "cand_Configuration_adv.h", tunekit::test::read_text(tunekit::test::dataset("firmware/Configuration_adv.h")));
  auto run = tunekit::test::run_cli({"export", "-f", "marlin", "-c", cfg, results, "--json"});
  INFO(run.err);
  REQUIRE(run.code == 0);
  auto env = nlohmann::json::parse(run.out);
  CHECK(env["results"]["settings"]["shapers"]["x"]["type"] == "zv");
  CHECK(env["results"]["settings"]["shapers"]["x"]["freq_hz"] == 44.2);
  const std::string rrf_cfg = tunekit::test::write_scratch("cand_config.g", "M584 X0 Y1 E3\n");
  run = tunekit::test::run_cli({"export", "-f", "rrf", "-c", rrf_cfg, results, "--json"});
  INFO(run.err);
  REQUIRE(run.code == 0);
  env = nlohmann::json::parse(run.out);
  CHECK(env["results"]["settings"]["shapers"]["x"]["type"] == "mzv");
}
