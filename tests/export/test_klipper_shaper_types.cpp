// printer.cfg with Klipper's parameterized input shapers ("mzv(n=4,t=0.9)", D. Butyugin,
// klippy/extras/shaper_defs.py, Klipper 2026): editing other options leaves them as written.
#include <catch2/catch.hpp>

#include <string>

#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"

using namespace tunekit::firmware;

namespace {

const std::string kBody =
    "[extruder]\n"
    "pressure_advance: 0.05\n"
    "\n"
    "[input_shaper]\n"
    "shaper_type_x: mzv(n=4,t=0.9)\n"
    "shaper_freq_x: 61.5\n"
    "shaper_type_y = ei(v_tol = 0.1)   # by hand\n"
    "shaper_freq_y = 47.25\n";

const std::string kSaveConfig =
    "[extruder]\n"
    "pressure_advance: 0.05\n"
    "\n"
    "#*# <---------------------- SAVE_CONFIG ---------------------->\n"
    "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
    "#*#\n"
    "#*# [input_shaper]\n"
    "#*# shaper_type_x = mzv(n=4,t=0.9)\n"
    "#*# shaper_freq_x = 61.5\n";

}  // namespace

TEST_CASE("a parameterized shaper type in printer.cfg survives an edit of other options", "[export][klipper]") {
  CompensatorSettings s;
  s.pa_k_s = 0.0425;
  const auto r = export_config_text(ExportFirmware::klipper, kBody, "printer.cfg", s);
  std::string expected = kBody;
  expected.replace(expected.find("pressure_advance: 0.05"), 22, "pressure_advance: 0.0425");
  CHECK(r.updated == expected);
  const auto block = export_config_text(ExportFirmware::klipper, kSaveConfig, "printer.cfg", s);
  CHECK(block.updated.find("#*# shaper_type_x = mzv(n=4,t=0.9)\n#*# shaper_freq_x = 61.5\n") != std::string::npos);
  CHECK(block.updated.find("pressure_advance: 0.0425\n") != std::string::npos);
}

TEST_CASE("a shaper exported for one axis replaces only that axis' parameterized type", "[export][klipper]") {
  CompensatorSettings s;
  s.shapers["y"] = {"ei", 52.4, 0.1};
  const auto r = export_config_text(ExportFirmware::klipper, kBody, "printer.cfg", s);
  CHECK(r.updated.find("shaper_type_x: mzv(n=4,t=0.9)\nshaper_freq_x: 61.5\n") != std::string::npos);
  CHECK(r.updated.find("shaper_type_y = ei   # by hand\n") != std::string::npos);
  bool reported = false;
  for (const auto& c : r.changes)
    if (c.key == "[input_shaper] shaper_type_y") reported = c.old_value == "ei(v_tol = 0.1)" && c.new_value == "ei";
  CHECK(reported);
  // Exported again: nothing left to change.
  CHECK_FALSE(export_config_text(ExportFirmware::klipper, r.updated, "printer.cfg", s).changed());
}
