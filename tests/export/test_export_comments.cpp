// A changed line's trailing comment described the old value: export replaces it with a short
// tunekit note (what set it, from which results, when); unchanged lines and comments stay.
#include <catch2/catch.hpp>

#include <string>

#include "test_support.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"

using tunekit::firmware::replace_trailing_comment;

TEST_CASE("replace_trailing_comment: a changed value's comment becomes the note, other comments stay") {
  const std::vector<std::string> klipper{"#", ";"};
  CHECK(replace_trailing_comment("pressure_advance: 0.05   ; tuned by hand with the tower test",
                                 "pressure_advance: 0.041   ; tuned by hand with the tower test", klipper,
                                 "NOTE") == "pressure_advance: 0.041   ; NOTE");
  CHECK(replace_trailing_comment("shaper_freq_x: 40 # old", "shaper_freq_x: 45.2 # old", klipper, "NOTE") ==
        "shaper_freq_x: 45.2 # NOTE");
  // No comment, no note, or no change: the edit is kept as it is.
  CHECK(replace_trailing_comment("pressure_advance: 0.05", "pressure_advance: 0.04", klipper, "NOTE") ==
        "pressure_advance: 0.04");
  CHECK(replace_trailing_comment("pressure_advance: 0.05 ; x", "pressure_advance: 0.04 ; x", klipper, "") ==
        "pressure_advance: 0.04 ; x");
  // Marlin: uncommenting a feature keeps its comment; a new value replaces it.
  const std::vector<std::string> marlin{"//"};
  CHECK(replace_trailing_comment("//#define LIN_ADVANCE          // Linear Advance",
                                 "#define LIN_ADVANCE          // Linear Advance", marlin,
                                 "NOTE") == "#define LIN_ADVANCE          // Linear Advance");
  CHECK(replace_trailing_comment("  #define ADVANCE_K 0.22    // Unit: mm compression per 1mm/s extruder speed",
                                 "  #define ADVANCE_K 0.05    // Unit: mm compression per 1mm/s extruder speed", marlin,
                                 "NOTE") == "  #define ADVANCE_K 0.05    // NOTE");
  // RepRapFirmware: the ';' comment after the parameters.
  CHECK(replace_trailing_comment("M572 D0 S0.05 ; PA from the tower", "M572 D0 S0.03 ; PA from the tower", {";"},
                                 "NOTE") == "M572 D0 S0.03 ; NOTE");
}

TEST_CASE("tunekit export over a hand-tuned pressure_advance with a comment writes the new value with a tunekit note") {
  const std::string cfg = tunekit::test::write_scratch(
      "comment_printer.cfg",
      "[extruder]\nstep_pin: PB3\npressure_advance: 0.05   ; tuned by hand with the tower test\n"
      "max_extrude_only_distance: 100 ; unrelated, unchanged\n");
  const auto r = tunekit::test::run_cli({"export", "-f", "klipper", "-c", cfg, "--pa-k", "0.041", "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string after = tunekit::test::read_text(cfg);
  CHECK(after.find("tuned by hand") == std::string::npos);
  CHECK(after.find("pressure_advance: 0.041   ; set by tunekit export from the command line on 20") !=
        std::string::npos);
  CHECK(after.find("max_extrude_only_distance: 100 ; unrelated, unchanged\n") != std::string::npos);
  // Without a note (the library default) the comment is kept as before.
  tunekit::firmware::CompensatorSettings s;
  s.pa_k_s = 0.041;
  const auto kept = tunekit::firmware::export_config_text(tunekit::firmware::ExportFirmware::klipper,
                                                          "[extruder]\npressure_advance: 0.05 ; x\n", "p.cfg", s);
  CHECK(kept.updated == "[extruder]\npressure_advance: 0.041 ; x\n");
}
