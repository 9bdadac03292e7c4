// Where each firmware reads a value (configuration precedence) and which values it accepts
// (limits), written from the firmwares' own source:
//   Klipper v0.13 klippy/configfile.py: ConfigAutoSave._find_autosave_data (the block is read only
//     under its exact AUTOSAVE_HEADER, every later line prefixed "#*# "), _strip_duplicates (a block
//     option that the body or an include also sets is commented out at load: the body wins),
//     ConfigFileReader._parse_config/_resolve_include (includes read where they stand, later
//     options override earlier ones; a missing non-glob include is an error).
//   Marlin MarlinCore.cpp setup(): settings.first_load() loads EEPROM over the compiled defaults.
//   RepRapFirmware GCodes2.cpp case 501 runs config-override.g where config.g's M501 stands;
//     GCodes.cpp WriteConfigOverrideFile (M500) never writes M572 or M593.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

using namespace tunekit;
using namespace tunekit::firmware;

namespace {

constexpr const char* kHeader =
    "#*# <---------------------- SAVE_CONFIG ---------------------->\n"
    "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
    "#*#\n";

/// Concatenation (GCC 12 warns falsely on chained std::string + literal: -Warray-bounds).
std::string cat(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (const auto p : parts) out.append(p.data(), p.size());
  return out;
}

void write(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

bool any_contains(const std::vector<std::string>& v, const std::string& s) {
  for (const auto& x : v)
    if (x.find(s) != std::string::npos) return true;
  return false;
}

std::string refusal(ExportFirmware fw, const CompensatorSettings& s, const std::string& text = "",
                    const std::string& path = "cfg") {
  try {
    if (text.empty()) validate_settings(fw, s);  // the limits alone
    else export_config_text(fw, text, path, s);
  } catch (const InputError& e) {
    return e.message();
  }
  return {};
}

}  // namespace

TEST_CASE("Klipper: an option in the body and in SAVE_CONFIG is written in the body, which Klipper uses") {
  // configfile.py _strip_duplicates comments out the block's pressure_advance: 0.05 is in force.
  const std::string cfg =
      cat({"[extruder]\npressure_advance: 0.05\n\n", kHeader, "#*# [extruder]\n#*# pressure_advance = 0.08\n"});
  CompensatorSettings s;
  s.pa_k_s = 0.4497;
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated ==
        cat({"[extruder]\npressure_advance: 0.4497\n\n", kHeader, "#*# [extruder]\n#*# pressure_advance = 0.08\n"}));
  REQUIRE(r.changes.size() == 1);
  CHECK(r.changes[0].line == 2);
  // No warning claims the block overrides the body; the block copy is reported as ignored.
  CHECK_FALSE(any_contains(r.warnings, "overridden by the SAVE_CONFIG"));
  CHECK(any_contains(r.warnings, "p.cfg:8"));
  CHECK(any_contains(r.warnings, "ignored by Klipper"));
  CHECK(any_contains(r.notes, "RESTART"));
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, "p.cfg", s).changed());
}

TEST_CASE("Klipper: an option only in SAVE_CONFIG is edited there") {
  const std::string cfg = cat({"[printer]\nkinematics: corexy\n\n", kHeader,
                               "#*# [input_shaper]\n#*# shaper_type_x = ei\n#*# shaper_freq_x = 40\n"});
  CompensatorSettings s;
  s.shapers["x"] = {"mzv", 49, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated == cat({"[printer]\nkinematics: corexy\n\n", kHeader,
                          "#*# [input_shaper]\n#*# shaper_type_x = mzv\n#*# shaper_freq_x = 49\n"
                          "#*# damping_ratio_x = 0.1\n"}));
}

TEST_CASE("Klipper: a section in the body and another option in SAVE_CONFIG: each value where Klipper reads it") {
  // [input_shaper] shaper_freq_x is in the body, shaper_type_x only in the block.
  const std::string cfg = cat({"[input_shaper]\nshaper_freq_x: 40\n\n", kHeader,
                               "#*# [input_shaper]\n#*# shaper_type_x = ei\n#*# shaper_freq_x = 45\n"});
  CompensatorSettings s;
  s.shapers["x"] = {"mzv", 49, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated == cat({"[input_shaper]\nshaper_freq_x: 49\ndamping_ratio_x: 0.1\n\n", kHeader,
                          "#*# [input_shaper]\n#*# shaper_type_x = mzv\n#*# shaper_freq_x = 45\n"}));
}

TEST_CASE("Klipper: a value set in an included file is overridden after the includes, in the body") {
  const std::string dir = tunekit::test::scratch_dir("klipper_include");
  write(dir + "/shaper.cfg", "[input_shaper]\nshaper_type_x: ei\nshaper_freq_x: 55\n");
  const std::string cfg = cat(
      {"[include shaper.cfg]\n\n[printer]\nkinematics: corexy\n\n", kHeader, "#*# [extruder]\n#*# pid_kp = 26.2\n"});
  const std::string path = dir + "/printer.cfg";
  write(path, cfg);
  CompensatorSettings s;
  s.shapers["x"] = {"mzv", 49, 0.1};
  const auto r = export_config_file(ExportFirmware::klipper, path, s);
  // Read in Klipper's order, the body's section comes after the include: it wins. The block
  // stays the file's tail (anything after its header would make Klipper ignore it).
  CHECK(r.updated == cat({"[include shaper.cfg]\n\n[printer]\nkinematics: corexy\n\n[input_shaper]\n"
                          "shaper_type_x: mzv\nshaper_freq_x: 49\ndamping_ratio_x: 0.1\n\n",
                          kHeader, "#*# [extruder]\n#*# pid_kp = 26.2\n"}));
  CHECK(any_contains(r.warnings, "shaper.cfg:3"));
  CHECK(any_contains(r.warnings, "included file"));
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, path, s).changed());
}

TEST_CASE("Klipper: a SAVE_CONFIG block Klipper does not read is not written into") {
  // A line after the header without the "#*# " prefix: _find_autosave_data gives up on the block.
  const std::string cfg =
      cat({"[printer]\nkinematics: corexy\n\n", kHeader, "#*# [extruder]\n#*#pressure_advance = 0.08\n"});
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated == cat({cfg, "\n[extruder]\npressure_advance: 0.05\n"}));
  CHECK(any_contains(r.warnings, "not read by Klipper"));
}

TEST_CASE("Klipper: a missing include is reported (Klipper refuses to start)") {
  const std::string dir = tunekit::test::scratch_dir("klipper_missing_include");
  const std::string path = dir + "/printer.cfg";
  write(path, "[include mainsail.cfg]\n[printer]\nkinematics: corexy\n");
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  const auto r = export_config_file(ExportFirmware::klipper, path, s);
  CHECK(any_contains(r.warnings, "mainsail.cfg does not exist"));
}

TEST_CASE("the bundled Klipper printer.cfg is complete: no includes, a [stepper_z]") {
  const std::string text = tunekit::test::read_text(tunekit::test::dataset("firmware/printer.cfg"));
  CHECK(text.find("[include") == std::string::npos);
  for (const char* sec : {"[mcu]", "[printer]", "[stepper_x]", "[stepper_y]", "[stepper_z]", "[extruder]"}) {
    INFO(sec);
    CHECK(text.find(sec) != std::string::npos);
  }
}

TEST_CASE("Marlin: the export states that EEPROM values win until M502 and M500") {
  const std::string path = tunekit::test::dataset("firmware/Configuration_adv.h");
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  const auto r = export_config_file(ExportFirmware::marlin, path, s);
  REQUIRE(r.changed());
  CHECK(any_contains(r.notes, "EEPROM"));
  CHECK(any_contains(r.notes, "M502"));
  CHECK(any_contains(r.notes, "M500"));
  CHECK(r.gcode.find("M500") != std::string::npos);
}

TEST_CASE("Marlin: a shaper frequency below SHAPING_MIN_FREQ is refused with the reason") {
  const std::string text =
      "#define INPUT_SHAPING_X\n#define SHAPING_FREQ_X 40\n#define SHAPING_ZETA_X 0.15f\n#define SHAPING_MIN_FREQ 30\n";
  CompensatorSettings s;
  s.shapers["x"] = {"zv", 25, 0.1};
  const std::string why = refusal(ExportFirmware::marlin, s, text, "Configuration_adv.h");
  CHECK(why.find("SHAPING_MIN_FREQ") != std::string::npos);
  s.shapers["x"].freq_hz = 35;
  CHECK(refusal(ExportFirmware::marlin, s, text, "Configuration_adv.h").empty());
}

TEST_CASE("RepRapFirmware: config-override.g setting M572 after config.g's line is refused with the reason") {
  const std::string dir = tunekit::test::scratch_dir("rrf_override");
  const std::string path = dir + "/config.g";
  write(path, "M584 X0 Y1 E3\nM572 D0 S0.05\nM501\n");
  write(dir + "/config-override.g", "; config-override.g file generated in response to M500\nM572 D0 S0.1\n");
  CompensatorSettings s;
  s.pa_k_s = 0.07;
  std::string why;
  try {
    export_config_file(ExportFirmware::rrf, path, s);
  } catch (const InputError& e) {
    why = e.message();
  }
  CHECK(why.find("config-override.g") != std::string::npos);
  CHECK(why.find("M501") != std::string::npos);

  SECTION("a line after M501 runs after config-override.g and is in force") {
    write(path, "M584 X0 Y1 E3\nM501\nM572 D0 S0.05\n");
    const auto r = export_config_file(ExportFirmware::rrf, path, s);
    CHECK(r.updated == "M584 X0 Y1 E3\nM501\nM572 D0 S0.07\n");
  }
  SECTION("without that line in config-override.g config.g's value is in force") {
    write(dir + "/config-override.g", "; config-override.g file generated in response to M500\nM307 H0 R2.4\n");
    const auto r = export_config_file(ExportFirmware::rrf, path, s);
    CHECK(r.updated == "M584 X0 Y1 E3\nM572 D0 S0.07\nM501\n");
    CHECK(any_contains(r.notes, "config.g"));
  }
}

TEST_CASE("every bound of the limits tables: in range accepted, out of range refused with bound and source") {
  using namespace tunekit::firmware::limits;
  // Klipper's per-shaper damping maxima (klippy/extras/shaper_defs.py:146-159).
  for (const auto& sh : kKlipperShapers) {
    INFO(sh.firmware_name);
    CompensatorSettings s;
    s.shapers["x"] = {sh.tunekit_name, 50, sh.max_damping};
    CHECK(refusal(ExportFirmware::klipper, s).empty());
    s.shapers["x"].damping = sh.max_damping + 0.005;
    const std::string why = refusal(ExportFirmware::klipper, s);
    std::ostringstream bound;
    bound << "at most " << sh.max_damping;
    CHECK(why.find(bound.str()) != std::string::npos);
    CHECK(why.find("shaper_defs.py") != std::string::npos);
  }
  CompensatorSettings s;
  // Klipper: pressure_advance >= 0, 0 < smooth_time <= 0.2 (klippy/kinematics/extruder.py:14-16).
  s.pa_k_s = -0.01;
  CHECK_FALSE(refusal(ExportFirmware::klipper, s).empty());
  s.pa_k_s = 0;
  CHECK(refusal(ExportFirmware::klipper, s).empty());
  s.pa_smooth_s = kKlipperSmoothTimeMax_s;
  CHECK(refusal(ExportFirmware::klipper, s).empty());
  s.pa_smooth_s = kKlipperSmoothTimeMax_s + 0.001;
  CHECK(refusal(ExportFirmware::klipper, s).find("extruder.py") != std::string::npos);
  s.pa_smooth_s = 0.0;
  CHECK_FALSE(refusal(ExportFirmware::klipper, s).empty());
  // Klipper has no zvdd.
  s = {};
  s.shapers["x"] = {"zvdd", 50, 0.1};
  CHECK(refusal(ExportFirmware::klipper, s).find("zvdd") != std::string::npos);

  // Marlin: M900 K 0..10 (M900.cpp), U 0..0.5, M593 D 0..1 (M593.cpp), classic shaping ZV only.
  s = {};
  s.pa_k_s = kMarlinAdvanceKMax;
  CHECK(refusal(ExportFirmware::marlin, s).empty());
  s.pa_k_s = kMarlinAdvanceKMax + 0.01;
  CHECK(refusal(ExportFirmware::marlin, s).find("M900.cpp") != std::string::npos);
  s = {};
  s.pa_smooth_s = kMarlinAdvanceTauMax_s;
  CHECK(refusal(ExportFirmware::marlin, s).empty());
  s.pa_smooth_s = kMarlinAdvanceTauMax_s + 0.01;
  CHECK_FALSE(refusal(ExportFirmware::marlin, s).empty());
  s = {};
  s.shapers["x"] = {"zv", 40, 0.99};
  CHECK(refusal(ExportFirmware::marlin, s).empty());
  s.shapers["x"].damping = 1.0;
  CHECK_FALSE(refusal(ExportFirmware::marlin, s).empty());
  s.shapers["x"] = {"mzv", 40, 0.1};
  CHECK(refusal(ExportFirmware::marlin, s).find("ZV only") != std::string::npos);

  // RepRapFirmware: M593 F from StepClockRate/(2*65535) to 1000 Hz, S 0..0.99 (AxisShaper.cpp:81-97),
  // shapers mzv zvd zvdd zvddd ei2 ei3 (AxisShaper.h; no zv, no ei); M572 S >= 0.
  s = {};
  s.shapers["x"] = {"mzv", kRrfShaperFreqMin_hz + 0.01, kRrfShaperZetaMax};
  CHECK(refusal(ExportFirmware::rrf, s).empty());
  s.shapers["x"].freq_hz = kRrfShaperFreqMin_hz - 0.01;
  CHECK(refusal(ExportFirmware::rrf, s).find("AxisShaper.cpp") != std::string::npos);
  s.shapers["x"].freq_hz = kRrfShaperFreqMax_hz + 1;
  CHECK_FALSE(refusal(ExportFirmware::rrf, s).empty());
  s.shapers["x"] = {"mzv", 40, kRrfShaperZetaMax + 0.005};
  CHECK(refusal(ExportFirmware::rrf, s).find("at most 0.99") != std::string::npos);
  for (const char* missing : {"zv", "ei"}) {
    s.shapers["x"] = {missing, 40, 0.1};
    CHECK_FALSE(refusal(ExportFirmware::rrf, s).empty());
  }
  s = {};
  s.pa_k_s = -0.001;
  CHECK_FALSE(refusal(ExportFirmware::rrf, s).empty());
}

TEST_CASE("the firmwares' shaper lists") {
  using namespace tunekit::firmware::limits;
  CHECK(shaper_list(ExportFirmware::klipper) == "zv, mzv, zvd, ei, 2hump_ei, 3hump_ei");
  CHECK(shaper_list(ExportFirmware::marlin) == "zv");
  CHECK(shaper_list(ExportFirmware::marlin, true) == "ZV, ZVD, ZVDD, ZVDDD, EI, 2HEI, 3HEI, MZV");
  CHECK(shaper_list(ExportFirmware::rrf) == "mzv, zvd, zvdd, zvddd, ei2, ei3");
  CHECK(firmware_shaper_name(ExportFirmware::rrf, "2hump_ei") == "ei2");
}
