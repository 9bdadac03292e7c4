// Firmware configuration editing: exact resulting lines, nothing else changed, idempotence,
// line endings, refusal of out-of-range values, and crash safety of the writer.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"

using namespace tunekit;
using namespace tunekit::firmware;

namespace {

/// Replaces the one occurrence of `from` in `text` (fails the test if it is not unique).
std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  REQUIRE(text.find(from, at + 1) == std::string::npos);
  return text.replace(at, from.size(), to);
}

std::string to_crlf(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\n') out += '\r';
    out += c;
  }
  return out;
}

CompensatorSettings klipper_settings() {
  CompensatorSettings s;
  s.pa_k_s = 0.0425;
  s.pa_smooth_s = 0.002;
  s.shapers["x"] = {"mzv", 52.4, 0.08};
  s.shapers["y"] = {"ei", 38.1, 0.12};
  return s;
}

}  // namespace

TEST_CASE("Klipper printer.cfg: values land where they take effect, everything else is byte-identical") {
  const std::string path = tunekit::test::dataset("firmware/printer.cfg");
  const std::string original = tunekit::test::read_text(path);
  const auto r = export_config_text(ExportFirmware::klipper, original, path, klipper_settings());

  // Expected file, built from the original by the edits the rules call for.
  std::string expected = original;
  // [extruder] pressure_advance is set in the section (not in SAVE_CONFIG): edited in place,
  // keeping the separator and the inline comment; the smooth time is added to that section.
  expected = replace_once(expected, "pressure_advance: 0.05   ; tuned by hand with the tower test\n",
                          "pressure_advance: 0.0425   ; tuned by hand with the tower test\n"
                          "pressure_advance_smooth_time: 0.002\n");
  // [input_shaper] exists only in the SAVE_CONFIG block: its values are edited there, the
  // missing ones added to the block's section.
  expected = replace_once(expected, "#*# shaper_freq_x = 48.6\n",
                          "#*# shaper_freq_x = 52.4\n"
                          "#*# damping_ratio_x = 0.08\n"
                          "#*# shaper_type_y = ei\n"
                          "#*# shaper_freq_y = 38.1\n"
                          "#*# damping_ratio_y = 0.12\n");
  CHECK(r.updated == expected);
  CHECK(r.changed());
  // The macro that mentions pressure advance is untouched (also covered by the equality).
  CHECK(r.updated.find("    SET_PRESSURE_ADVANCE ADVANCE=0.07\n") != std::string::npos);
  // Diff preview names the changed lines.
  CHECK(r.diff.rfind("--- " + path + "\n", 0) == 0);
  CHECK(r.diff.find("\n-pressure_advance: 0.05   ; tuned by hand with the tower test\n") != std::string::npos);
  CHECK(r.diff.find("\n+pressure_advance: 0.0425   ; tuned by hand with the tower test\n") != std::string::npos);
  CHECK(r.diff.find("\n+#*# shaper_type_y = ei\n") != std::string::npos);
  CHECK(r.gcode.find("SET_PRESSURE_ADVANCE ADVANCE=0.0425 SMOOTH_TIME=0.002") != std::string::npos);
  // The shaper type was "mzv" already: not reported as a change.
  for (const auto& c : r.changes) CHECK(c.key != "[input_shaper] shaper_type_x");

  SECTION("a second run changes nothing") {
    const auto again = export_config_text(ExportFirmware::klipper, r.updated, path, klipper_settings());
    CHECK(again.updated == r.updated);
    CHECK_FALSE(again.changed());
    CHECK(again.diff.empty());
    CHECK(again.changes.empty());
  }
  SECTION("CRLF line endings are kept, also on added lines") {
    const auto crlf = export_config_text(ExportFirmware::klipper, to_crlf(original), path, klipper_settings());
    CHECK(crlf.updated == to_crlf(expected));
  }
}

TEST_CASE("Klipper: a value set above and in the SAVE_CONFIG block is edited above, where Klipper reads it") {
  // klippy/configfile.py _strip_duplicates comments out the block's copy at load: the body wins.
  const std::string cfg =
      "[extruder]\n"
      "pressure_advance = 0.1\n"
      "\n"
      "#*# <---------------------- SAVE_CONFIG ---------------------->\n"
      "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
      "#*#\n"
      "#*# [extruder]\n"
      "#*# pressure_advance = 0.08\n";
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  s.shapers["x"] = {"zv", 40, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated ==
        "[extruder]\n"
        "pressure_advance = 0.05\n"
        "\n"
        "#*# <---------------------- SAVE_CONFIG ---------------------->\n"
        "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
        "#*#\n"
        "#*# [extruder]\n"
        "#*# pressure_advance = 0.08\n"
        "#*#\n"
        "#*# [input_shaper]\n"
        "#*# shaper_type_x = zv\n"
        "#*# shaper_freq_x = 40\n"
        "#*# damping_ratio_x = 0.1\n");
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("p.cfg:8") != std::string::npos);
  CHECK(r.warnings[0].find("ignored by Klipper") != std::string::npos);
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, "p.cfg", s).changed());
}

TEST_CASE(
    "Klipper: without a SAVE_CONFIG block a missing section is appended, and a missing final newline is handled") {
  const std::string cfg = "[printer]\nkinematics: cartesian";
  CompensatorSettings s;
  s.shapers["y"] = {"2hump_ei", 61.25, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated ==
        "[printer]\nkinematics: cartesian\n\n[input_shaper]\nshaper_type_y: 2hump_ei\nshaper_freq_y: 61.25\n"
        "damping_ratio_y: 0.1\n");
  CHECK(r.diff.find("\\ No newline at end of file") != std::string::npos);
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, "p.cfg", s).changed());
}

TEST_CASE("Marlin Configuration_adv.h: features enabled, values set, comments and columns kept") {
  const std::string path = tunekit::test::dataset("firmware/Configuration_adv.h");
  const std::string original = tunekit::test::read_text(path);
  CompensatorSettings s;
  s.pa_k_s = 0.0425;
  s.pa_smooth_s = 0.0011;
  s.shapers["x"] = {"zv", 44, 0.1};
  s.shapers["y"] = {"zv", 41.5, 0.12};
  const auto r = export_config_text(ExportFirmware::marlin, original, path, s);

  std::string expected = original;
  expected = replace_once(expected, "//#define INPUT_SHAPING_X\n", "#define INPUT_SHAPING_X\n");
  expected = replace_once(expected, "//#define INPUT_SHAPING_Y\n", "#define INPUT_SHAPING_Y\n");
  expected = replace_once(expected, "#define SHAPING_FREQ_X  40          //", "#define SHAPING_FREQ_X  44          //");
  expected = replace_once(expected, "#define SHAPING_ZETA_X  0.15f       //", "#define SHAPING_ZETA_X  0.1f        //");
  expected = replace_once(expected, "#define SHAPING_FREQ_Y  40          //", "#define SHAPING_FREQ_Y  41.5        //");
  expected = replace_once(expected, "#define SHAPING_ZETA_Y  0.15f       //", "#define SHAPING_ZETA_Y  0.12f       //");
  expected = replace_once(expected, "//#define LIN_ADVANCE\n", "#define LIN_ADVANCE\n");
  expected = replace_once(expected, "#define ADVANCE_K { 0.22 }    //", "#define ADVANCE_K { 0.0425 }  //");
  expected = replace_once(expected, "#define ADVANCE_K 0.22        //", "#define ADVANCE_K 0.0425      //");
  expected = replace_once(expected, "//#define SMOOTH_LIN_ADVANCE    //", "#define SMOOTH_LIN_ADVANCE    //");
  expected = replace_once(expected, "#define ADVANCE_TAU 0.02      //", "#define ADVANCE_TAU 0.0011    //");
  CHECK(r.updated == expected);
  // Options that were not asked for stay commented out.
  CHECK(r.updated.find("//#define ADVANCE_K_EXTRA") != std::string::npos);
  CHECK(r.updated.find("//#define SHAPING_MENU") != std::string::npos);
  CHECK(r.gcode == "M900 K0.0425 U0.0011\nM593 X F44 D0.1\nM593 Y F41.5 D0.12\nM500\n");
  CHECK(r.warnings.empty());

  const auto again = export_config_text(ExportFirmware::marlin, r.updated, path, s);
  CHECK_FALSE(again.changed());
  CHECK(again.changes.empty());
}

TEST_CASE("Marlin 2.1.2 layout without SMOOTH_LIN_ADVANCE: K written, tau reported as not writable") {
  const std::string cfg =
      "//#define LIN_ADVANCE\n"
      "#if ENABLED(LIN_ADVANCE)\n"
      "  #define ADVANCE_K 0.22    // (mm)\n"
      "#endif\n";
  CompensatorSettings s;
  s.pa_k_s = 0.05;
  s.pa_smooth_s = 0.002;
  const auto r = export_config_text(ExportFirmware::marlin, cfg, "Configuration_adv.h", s);
  CHECK(r.updated == "#define LIN_ADVANCE\n#if ENABLED(LIN_ADVANCE)\n  #define ADVANCE_K 0.05    // (mm)\n#endif\n");
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("SMOOTH_LIN_ADVANCE") != std::string::npos);
  CHECK(r.gcode == "M900 K0.05\nM500\n");
}

TEST_CASE("RepRapFirmware config.g: M572 edited in place, M593 added after it") {
  const std::string path = tunekit::test::dataset("firmware/config.g");
  const std::string original = tunekit::test::read_text(path);
  CompensatorSettings s;
  s.pa_k_s = 0.0425;
  s.shapers["x"] = {"mzv", 52.4, 0.08};
  s.shapers["y"] = {"mzv", 52.4, 0.08};
  const auto r = export_config_text(ExportFirmware::rrf, original, path, s);
  const std::string expected =
      replace_once(original, "M572 D0 S0.05                                ; pressure advance (s)\n",
                   "M572 D0 S0.0425                                ; pressure advance (s)\n"
                   "M593 P\"mzv\" F52.4 S0.08 ; input shaping (Hz, damping ratio)\n");
  CHECK(r.updated == expected);
  CHECK(r.warnings.empty());
  CHECK(r.gcode == "M572 D0 S0.0425\nM593 P\"mzv\" F52.4 S0.08\n");
  CHECK_FALSE(export_config_text(ExportFirmware::rrf, r.updated, path, s).changed());

  SECTION("an existing M593 has its parameters rewritten; X and Y differing loses one of them") {
    CompensatorSettings s2;
    s2.shapers["x"] = {"2hump_ei", 61, 0.1};
    s2.shapers["y"] = {"zvd", 38.1, 0.05};
    const auto r2 = export_config_text(ExportFirmware::rrf, r.updated, path, s2);
    CHECK(r2.updated == replace_once(r.updated, "M593 P\"mzv\" F52.4 S0.08 ;", "M593 P\"zvd\" F38.1 S0.05 ;"));
    REQUIRE(r2.warnings.size() == 1);
    CHECK(r2.warnings[0].find("one input shaper") != std::string::npos);
  }
}

TEST_CASE("RepRapFirmware: new commands go after the drive block when the file has neither") {
  const std::string cfg =
      "M92 X80 Y80 E420 ; steps\r\n"
      "M201 X3000 Y3000 E5000 ; accelerations\r\n"
      "M208 X220 Y220 S0\r\n"
      "M501\r\n";
  CompensatorSettings s;
  s.pa_k_s = 0.03;
  s.shapers["x"] = {"ei2", 48, 0.1};
  const auto r = export_config_text(ExportFirmware::rrf, cfg, "config.g", s);
  CHECK(r.updated ==
        "M92 X80 Y80 E420 ; steps\r\n"
        "M201 X3000 Y3000 E5000 ; accelerations\r\n"
        "M572 D0 S0.03 ; pressure advance (s)\r\n"
        "M593 P\"ei2\" F48 S0.1 ; input shaping (Hz, damping ratio)\r\n"
        "M208 X220 Y220 S0\r\n"
        "M501\r\n");
}

TEST_CASE("Out-of-range values and missing shaper types are refused with the reason") {
  auto refuse = [](ExportFirmware fw, const CompensatorSettings& s, const std::string& reason) {
    try {
      validate_settings(fw, s);
      FAIL("accepted: " << reason);
    } catch (const InputError& e) {
      CHECK(e.code() == ExitCode::bad_input);
      CHECK_THAT(e.message(), Catch::Contains(reason));
    }
  };
  CompensatorSettings k11;
  k11.pa_k_s = 10.5;
  refuse(ExportFirmware::marlin, k11, "0 to 10");
  CHECK_NOTHROW(validate_settings(ExportFirmware::klipper, k11));  // Klipper has no upper bound on K
  CompensatorSettings u;
  u.pa_smooth_s = 0.6;
  refuse(ExportFirmware::marlin, u, "0.5");
  refuse(ExportFirmware::klipper, u, "0.2");
  CompensatorSettings neg;
  neg.shapers["x"] = {"zv", -40, 0.1};
  refuse(ExportFirmware::klipper, neg, "frequency must be positive");
  CompensatorSettings zeta1;
  zeta1.shapers["y"] = {"mzv", 40, 1.0};
  refuse(ExportFirmware::klipper, zeta1, "below 1");
  CompensatorSettings mzv;
  mzv.shapers["x"] = {"mzv", 40, 0.1};
  refuse(ExportFirmware::marlin, mzv, "ZV only");
  CompensatorSettings zvdd;
  zvdd.shapers["x"] = {"zvdd", 40, 0.1};
  refuse(ExportFirmware::klipper, zvdd, "no 'zvdd'");
  CHECK_NOTHROW(validate_settings(ExportFirmware::rrf, zvdd));
  CompensatorSettings zv;
  zv.shapers["x"] = {"zv", 40, 0.1};
  refuse(ExportFirmware::rrf, zv, "no 'zv'");
  CompensatorSettings low;
  low.shapers["x"] = {"mzv", 5, 0.1};
  refuse(ExportFirmware::rrf, low, "7.15");
  CHECK(firmware_shaper_name(ExportFirmware::rrf, "3hump_ei") == "ei3");
}

TEST_CASE("The CLI refuses out-of-range values with exit 2 and leaves the file alone") {
  const std::string dir = tunekit::test::scratch_dir("export_refuse");
  const std::string cfg = dir + "/Configuration_adv.h";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/Configuration_adv.h"), cfg);
  const std::string before = tunekit::test::read_text(cfg);
  const std::vector<std::vector<std::string>> cases = {
      {"--pa-k", "10.5"},          {"--pa-k", "0.04", "--pa-smooth", "0.6"},
      {"--shaper-x", "zv:-40"},    {"--shaper-y", "zv:40:1.0"},
      {"--shaper-x", "ei:40:0.1"},
  };
  for (const auto& extra : cases) {
    std::vector<std::string> args = {"export", "--firmware", "marlin", "--config", cfg, "--write"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto run = tunekit::test::run_cli(args);
    INFO(extra.front() << " " << extra.back() << ": " << run.err);
    CHECK(run.code == 2);
    CHECK_THAT(run.err, Catch::StartsWith("tunekit: error:"));
    CHECK(run.out.empty());
  }
  CHECK(tunekit::test::read_text(cfg) == before);
  CHECK(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator{}) == 1);
}

TEST_CASE("A crash between writing the temporary file and the rename leaves the original intact") {
  const std::string dir = tunekit::test::scratch_dir("export_crash");
  const std::string cfg = dir + "/printer.cfg";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/printer.cfg"), cfg);
  const std::string before = tunekit::test::read_text(cfg);
  const auto r = export_config_file(ExportFirmware::klipper, cfg, klipper_settings());
  REQUIRE(r.changed());

  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    try {
      apply_export(r, [](const std::string& tmp) {
        // The new content is complete and durable in `tmp`: die before the rename.
        ::_exit(std::filesystem::file_size(tmp) > 0 ? 42 : 43);
      });
    } catch (...) {
    }
    ::_exit(1);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 42);
  CHECK(tunekit::test::read_text(cfg) == before);
  // The backup was made before the replacement started and holds the original bytes.
  int backups = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 4 && name.substr(name.size() - 4) == ".bak") {
      ++backups;
      CHECK(tunekit::test::read_text(e.path().string()) == before);
    }
  }
  CHECK(backups == 1);

  SECTION("a completed write replaces the file with exactly the new text") {
    const std::string backup = apply_export(r);
    CHECK(tunekit::test::read_text(cfg) == r.updated);
    CHECK(tunekit::test::read_text(backup) == before);
  }
}

TEST_CASE("Unified diff of line edits") {
  LineEditor ed("a\nb\nc\nd\ne\nf\ng\nh\ni\nj\n");
  ed.replace(1, "B");
  ed.insert_before(9, {"x"});
  CHECK(ed.render() == "a\nB\nc\nd\ne\nf\ng\nh\ni\nx\nj\n");
  CHECK(ed.unified_diff("/abs/f.txt", 1).rfind("--- /abs/f.txt\n+++ /abs/f.txt\n", 0) == 0);
  CHECK(ed.unified_diff("f.txt", 1) ==
        "--- a/f.txt\n+++ b/f.txt\n"
        "@@ -1,3 +1,3 @@\n a\n-b\n+B\n c\n"
        "@@ -9,2 +9,3 @@\n i\n+x\n j\n");
  CHECK(format_number(0.04, 4) == "0.04");
  CHECK(format_number(45.0, 2) == "45");
  CHECK(same_number("0.040", 0.04, 4));
  CHECK_FALSE(same_number("0.05", 0.04, 4));
  CHECK_FALSE(same_number("abc", 0.04, 4));
}

TEST_CASE(
    "Klipper: a Z shaper is written as shaper_type_z / shaper_freq_z / damping_ratio_z, other firmwares refuse it") {
  // Klipper's [input_shaper] reads the Z keys since its Z-axis input shaper (Butyugin, 2025).
  const std::string cfg = "[printer]\nkinematics: cartesian\n\n[input_shaper]\nshaper_freq_x: 48.6\n";
  CompensatorSettings s;
  s.shapers["z"] = {"2hump_ei", 63, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, cfg, "p.cfg", s);
  CHECK(r.updated == cfg + "shaper_type_z: 2hump_ei\nshaper_freq_z: 63\ndamping_ratio_z: 0.1\n");
  CHECK(r.gcode.find("SET_INPUT_SHAPER SHAPER_TYPE_Z=2hump_ei SHAPER_FREQ_Z=63 DAMPING_RATIO_Z=0.1") !=
        std::string::npos);
  bool noted = false;
  for (const auto& n : r.notes) noted = noted || n.find("older Klipper refuses to start") != std::string::npos;
  CHECK(noted);
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, "p.cfg", s).changed());
  // Klipper's bound on the damping of each shaper applies to Z too.
  CompensatorSettings wild = s;
  wild.shapers["z"].damping = 0.95;
  CHECK_THROWS_AS(validate_settings(ExportFirmware::klipper, wild), InputError);
  for (const auto fw : {ExportFirmware::kalico, ExportFirmware::marlin, ExportFirmware::rrf}) {
    try {
      validate_settings(fw, s);
      FAIL("accepted a Z shaper for " << to_string(fw));
    } catch (const InputError& e) {
      CHECK(e.code() == ExitCode::bad_input);
      CHECK_THAT(e.message(), Catch::Contains("exported for Klipper only"));
    }
  }
  CompensatorSettings e;
  e.shapers["e"] = {"zv", 40, 0.1};
  CHECK_THROWS_AS(validate_settings(ExportFirmware::klipper, e), InputError);
}
