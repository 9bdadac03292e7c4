// Machine profiles from Klipper's own stock printer configurations (datasets/klipper_configs, copied
// from Klipper's config/ folder): the limits Klipper computes from each file, value by value, hand
// checked against the file and Klipper's source (Kevin O'Connor et al., Klipper 3D printer
// firmware, klippy/kinematics/extruder.py, toolhead.py, stepper.py, kinematics/delta.py); every
// stock configuration of a kinematics tunekit supports imports; includes, the SAVE_CONFIG block and
// hostile values.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/profile_import.hpp"

using Catch::Matchers::Contains;
using tunekit::machine::MachineProfile;
using tunekit::test::dataset;

namespace {

/// Klipper's default extrude-only ratio for a 0.4 mm nozzle and 1.75 mm filament:
/// def_max_cross_section / filament_area = 4 * 0.4^2 / (pi * 0.875^2) (extruder.py).
const double kRatio04_175 = 4 * 0.4 * 0.4 / (std::numbers::pi * 0.875 * 0.875);

std::string klipper(const std::string& name) { return dataset("klipper_configs/" + name); }

void write(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

/// The error's location and message for importing `path`; FAIL if it imports.
tunekit::InputError import_error(const std::string& path) {
  try {
    (void)tunekit::machine::load_machine_profile(path);
  } catch (const tunekit::InputError& e) {
    return e;
  }
  FAIL("imported without an error: " << path);
  return tunekit::InputError("");
}

}  // namespace

TEST_CASE("Klipper: the Creality Ender-3 V2's stock printer.cfg gives Klipper's limits", "[profiles][klipper]") {
  const std::string path = klipper("printer-creality-ender3-v2-2020.cfg");
  const MachineProfile p = tunekit::machine::load_machine_profile(path);
  CHECK(p.firmware == "klipper");
  CHECK(p.kinematics == "cartesian");
  // [stepper_x] position_max: 235 (line 27), position_min default 0; [printer] max_velocity: 300,
  // max_accel: 3000 (lines 92-93), max_z_velocity: 5, max_z_accel: 100.
  CHECK(p.axis("x").min_mm == 0);
  CHECK(p.axis("x").max_mm == 235);
  CHECK(p.axis("y").max_mm == 235);
  CHECK(p.axis("z").max_mm == 250);
  CHECK(p.axis("x").max_velocity_mm_s == 300);
  CHECK(p.axis("x").max_accel_mm_s2 == 3000);
  CHECK(p.axis("z").max_velocity_mm_s == 5);
  CHECK(p.axis("z").max_accel_mm_s2 == 100);
  CHECK(p.print.max_accel_mm_s2 == 3000);
  CHECK(p.state.accel_in_force_mm_s2 == 3000);
  CHECK(p.state.minimum_cruise_ratio == 0.5);  // toolhead.py default
  // [extruder] nozzle 0.400, filament 1.750: Klipper's default extrude-only limits are
  // max_velocity * 4 d^2 / (pi (D/2)^2) = 300 * 0.26608 = 79.82 mm/s and
  // max_accel * 0.26608 = 3000 * 0.26608 = 798.24 mm/s^2; max_extrude_only_distance: 100.0 (line 52).
  CHECK(p.extruder.nozzle_diameter_mm == 0.4);
  CHECK(p.extruder.filament_diameter_mm == 1.75);
  CHECK(p.extruder.max_velocity_mm_s == Approx(79.8243).epsilon(1e-6));
  CHECK(p.extruder.max_accel_mm_s2 == Approx(798.2432).epsilon(1e-6));
  CHECK(p.extruder.max_accel_mm_s2 == Approx(3000 * kRatio04_175));
  CHECK(p.extruder.max_extrude_only_distance_mm == 100);
  CHECK(p.temperature.hotend_max_c == 250);  // [extruder] max_temp: 250
  CHECK(p.temperature.bed_max_c == 130);     // [heater_bed] max_temp: 130
  // rotation_distance 40, microsteps 16, 200 full steps: 80 steps/mm.
  CHECK(p.state.steps_per_mm_x == 80);
  CHECK(p.state.steps_per_mm_y == 80);
  // Not in any printer.cfg: tunekit's conservative hot-end flow (8 mm^3/s, below the 192 mm^3/s the
  // feed limit allows) and the print's line from the nozzle.
  CHECK(p.extruder.max_flow_mm3_s == 8);
  CHECK(p.print.line_width_mm == Approx(0.45));
  CHECK(p.print.layer_height_mm == Approx(0.2));
  CHECK_FALSE(p.sensors.accelerometer);
  CHECK(p.state.shaper.empty());
  // The profile is the one its TOML loads as: the loader's default for what the TOML leaves out
  // (max_accel_e_mm_s2 = the extruder's limit), Klipper's acceleration in force kept.
  CHECK(p.state.max_accel_e_mm_s2 == p.extruder.max_accel_mm_s2);

  // Every value names its source.
  CHECK(p.sources.at("print.max_accel_mm_s2") == path + ":93 [printer] max_accel: 3000");
  CHECK(p.sources.at("axes.x.max_mm") == path + ":27 [stepper_x] position_max: 235");
  CHECK_THAT(p.sources.at("extruder.max_accel_mm_s2"),
             Contains("Klipper default (klippy/kinematics/extruder.py): max_accel * 4 d^2 / (pi (D/2)^2)") &&
                 Contains("= 798.2"));
  CHECK_THAT(p.sources.at("extruder.max_flow_mm3_s"), Contains("tunekit default"));
  CHECK_THAT(p.sources.at("axes.x.min_mm"), Contains("klippy/stepper.py"));
  for (const char* key : {"axes.x.max_velocity_mm_s", "axes.z.max_accel_mm_s2", "extruder.max_velocity_mm_s",
                          "extruder.max_extrude_only_distance_mm", "temperature.hotend_max_c", "temperature.bed_max_c",
                          "firmware_state.steps_per_mm_x", "print.line_width_mm"})
    CHECK(p.sources.count(key) == 1);
}

TEST_CASE("Klipper: the Creality Ender-6's corexy printer.cfg gives Klipper's limits", "[profiles][klipper]") {
  const MachineProfile p = tunekit::machine::load_machine_profile(klipper("printer-creality-ender6-2020.cfg"));
  CHECK(p.kinematics == "corexy");
  CHECK(p.axis("x").max_mm == 260);
  CHECK(p.axis("y").max_mm == 260);
  CHECK(p.axis("z").max_mm == 400);
  CHECK(p.axis("x").max_velocity_mm_s == 500);
  CHECK(p.axis("x").max_accel_mm_s2 == 2000);
  CHECK(p.axis("z").max_velocity_mm_s == 10);
  CHECK(p.axis("z").max_accel_mm_s2 == 100);
  // 500 * 0.26608 = 133.04 mm/s, 2000 * 0.26608 = 532.16 mm/s^2; max_extrude_only_distance: 1000.0.
  CHECK(p.extruder.max_velocity_mm_s == Approx(133.0405).epsilon(1e-6));
  CHECK(p.extruder.max_accel_mm_s2 == Approx(532.1622).epsilon(1e-6));
  CHECK(p.extruder.max_extrude_only_distance_mm == 1000);
  CHECK(p.temperature.hotend_max_c == 260);
  CHECK(p.temperature.bed_max_c == 100);
}

TEST_CASE("Klipper: the Anycubic Kossel Plus's delta printer.cfg gives Klipper's build volume as a box",
          "[profiles][klipper][delta]") {
  const MachineProfile p = tunekit::machine::load_machine_profile(klipper("printer-anycubic-kossel-plus-2017.cfg"));
  CHECK(p.kinematics == "delta");
  // delta.py: max_xy = min(print_radius = delta_radius 134.4, arm_length 269 - 134.4 = 134.6,
  // ratio_to_xy(12) = 12 sqrt(269^2 / 145 - 0.00625^2) + 0.00625 - 134.4 = 133.677) = 133.677 mm;
  // tunekit's box is the square inside that circle: +-133.677 / sqrt(2) = +-94.524 mm.
  CHECK(p.axis("x").max_mm == Approx(94.52395).epsilon(1e-6));
  CHECK(p.axis("x").min_mm == Approx(-94.52395).epsilon(1e-6));
  CHECK(p.axis("y").max_mm == Approx(94.52395).epsilon(1e-6));
  // Heights: position_endstop 295.6 (towers b and c default to a's); the radius tapers above
  // limit_z = 295.6 + sqrt(269^2 - 134.4^2) - 269 = 259.619 mm, so Z ends there; minimum_z_position 0.
  CHECK(p.axis("z").min_mm == 0);
  CHECK(p.axis("z").max_mm == Approx(259.6185).epsilon(1e-6));
  CHECK(p.axis("x").max_velocity_mm_s == 500);
  CHECK(p.axis("x").max_accel_mm_s2 == 3000);
  CHECK(p.axis("z").max_velocity_mm_s == 200);  // [printer] max_z_velocity: 200
  CHECK(p.axis("z").max_accel_mm_s2 == 3000);   // max_z_accel defaults to max_accel (delta.py)
  CHECK(p.extruder.max_velocity_mm_s == Approx(133.0405).epsilon(1e-6));
  CHECK(p.extruder.max_accel_mm_s2 == Approx(798.2432).epsilon(1e-6));
  CHECK(p.extruder.max_extrude_only_distance_mm == 50);  // extruder.py default
  CHECK(p.temperature.hotend_max_c == 275);
  CHECK(p.temperature.bed_max_c == 130);
  CHECK_THAT(p.sources.at("axes.x.max_mm"), Contains("delta.py") && Contains("sqrt(2)"));
}

TEST_CASE("Klipper: every stock printer-*.cfg of a supported kinematics imports with finite positive limits",
          "[profiles][klipper]") {
  int imported = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dataset("klipper_configs"))) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("printer-", 0) != 0 || entry.path().extension() != ".cfg") continue;
    INFO(name);
    MachineProfile p;
    REQUIRE_NOTHROW(p = tunekit::machine::load_machine_profile(entry.path().string()));
    for (const char* axis : {"x", "y", "z"}) {
      const auto& a = p.axis(axis);
      CHECK(std::isfinite(a.min_mm));
      CHECK(std::isfinite(a.max_mm));
      CHECK(a.max_mm > a.min_mm);
      CHECK((std::isfinite(a.max_velocity_mm_s) && a.max_velocity_mm_s > 0));
      CHECK((std::isfinite(a.max_accel_mm_s2) && a.max_accel_mm_s2 > 0));
    }
    for (double v : {p.extruder.max_velocity_mm_s, p.extruder.max_accel_mm_s2, p.extruder.max_flow_mm3_s,
                     p.extruder.max_extrude_only_distance_mm, p.extruder.nozzle_diameter_mm,
                     p.extruder.filament_diameter_mm, p.print.max_accel_mm_s2, p.temperature.hotend_max_c,
                     p.temperature.bed_max_c, p.state.steps_per_mm_x, p.state.steps_per_mm_y})
      CHECK((std::isfinite(v) && v > 0));
    // The TOML written from it reads back to the same limits.
    const auto back = tunekit::machine::parse_machine_profile(tunekit::machine::machine_profile_toml(p), name);
    CHECK(back.axis("x").max_mm == p.axis("x").max_mm);
    CHECK(back.extruder.max_accel_mm_s2 == p.extruder.max_accel_mm_s2);
    CHECK(back.temperature.bed_max_c == p.temperature.bed_max_c);
    CHECK(back.kinematics == p.kinematics);
    ++imported;
  }
  CHECK(imported == 108);  // 90 cartesian, 8 corexy, 10 delta: all supported
}

TEST_CASE("Klipper: [include] reads globs relative to the including file, nested, later options winning",
          "[profiles][klipper][include]") {
  const std::string dir = tunekit::test::scratch_dir("klipper_include");
  write(dir + "/printer.cfg", "[include " + klipper("printer-creality-ender3-v2-2020.cfg") +
                                  "]\n[include parts/*.cfg]\n[include none/*.cfg]\n");
  write(dir + "/parts/10-speed.cfg", "[printer]\nmax_accel: 2000\n[include nested/limits.cfg]\n");
  write(dir + "/parts/nested/limits.cfg", "[extruder]\nmax_extrude_only_accel: 600\n");
  write(dir + "/parts/20-speed.cfg", "[printer]\nmax_accel: 1500   ; the later file wins\n");
  const MachineProfile p = tunekit::machine::load_machine_profile(dir + "/printer.cfg");
  CHECK(p.print.max_accel_mm_s2 == 1500);
  CHECK(p.sources.at("print.max_accel_mm_s2") ==
        dir + "/parts/20-speed.cfg:2 [printer] max_accel: 1500   ; the later file wins");
  CHECK(p.extruder.max_accel_mm_s2 == 600);
  CHECK(p.sources.at("extruder.max_accel_mm_s2") ==
        dir + "/parts/nested/limits.cfg:2 [extruder] max_extrude_only_accel: 600");
  CHECK(p.axis("x").max_mm == 235);  // from the included stock file

  write(dir + "/missing.cfg", "[printer]\nkinematics: cartesian\n[include nothere.cfg]\n");
  auto e = import_error(dir + "/missing.cfg");
  CHECK(e.location() == dir + "/missing.cfg:3");
  CHECK_THAT(e.message(), Contains("nothere.cfg does not exist"));

  write(dir + "/loop_a.cfg", "[printer]\nkinematics: cartesian\n[include loop_b.cfg]\n");
  write(dir + "/loop_b.cfg", "# b includes a again\n[include loop_a.cfg]\n");
  e = import_error(dir + "/loop_a.cfg");
  CHECK(e.location() == dir + "/loop_b.cfg:2");
  CHECK_THAT(e.message(), Contains("loops"));

  write(dir + "/self.cfg", "[include self.cfg]\n[printer]\n");
  CHECK_THAT(import_error(dir + "/self.cfg").message(), Contains("loops"));
}

TEST_CASE("Klipper: accelerometer, load cell and input shaper sections become sensors and firmware state",
          "[profiles][klipper][sensors]") {
  const std::string dir = tunekit::test::scratch_dir("klipper_sensors");
  write(dir + "/printer.cfg", "[include " + klipper("printer-creality-ender3-v2-2020.cfg") +
                                  "]\n"
                                  "[adxl345 bed]\ncs_pin: PA4\n"
                                  "[lis2dw toolhead]\ncs_pin: PB12\n"
                                  "[resonance_tester]\naccel_chip: lis2dw toolhead\nprobe_points: 100, 100, 20\n"
                                  "[load_cell probe]\nsensor_type: hx711\n"
                                  "[input_shaper]\nshaper_type: ei\nshaper_freq_x: 48.6\ndamping_ratio_x: 0.05\n");
  const MachineProfile p = tunekit::machine::load_machine_profile(dir + "/printer.cfg");
  CHECK(p.sensors.accelerometer);
  CHECK(p.sensors.accelerometer_chip == "lis2dw");  // the chip [resonance_tester] accel_chip names
  CHECK(p.sensors.accelerometer_name == "lis2dw toolhead");
  CHECK(p.sensors.accelerometer_rate_hz == 1600);  // lis2dw.py's rate
  CHECK(p.sensors.load_cell);
  CHECK(p.sensors.load_cell_name == "load_cell probe");
  // shaper_type ei for both axes, shaper_freq_y 0 (default): Y unshaped.
  CHECK(p.state.shaper.at("x") == "ei:48.6:0.05");
  CHECK(p.state.shaper.count("y") == 0);
  const auto back = tunekit::machine::parse_machine_profile(tunekit::machine::machine_profile_toml(p), "back.toml");
  CHECK(back.sensors.accelerometer_chip == "lis2dw");
  CHECK(back.sensors.accelerometer_name == "lis2dw toolhead");
  CHECK(back.sensors.load_cell_name == "load_cell probe");
  CHECK(back.state.shaper.at("x") == "ei:48.6:0.05");
}

TEST_CASE("Klipper: the SAVE_CONFIG block applies where the sections above do not set the option",
          "[profiles][klipper][save_config]") {
  const std::string stock = tunekit::test::read_text(klipper("printer-creality-ender3-v2-2020.cfg"));
  const std::string block =
      "\n#*# <---------------------- SAVE_CONFIG ---------------------->\n"
      "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.\n"
      "#*#\n"
      "#*# [extruder]\n"
      "#*# max_temp = 300\n"
      "#*# max_extrude_only_velocity = 45\n"
      "#*#\n"
      "#*# [input_shaper]\n"
      "#*# shaper_type_x = mzv\n"
      "#*# shaper_freq_x = 48.6\n"
      "#*# shaper_type_y = ei\n"
      "#*# shaper_freq_y = 39.2\n";
  const std::string dir = tunekit::test::scratch_dir("klipper_save_config");
  write(dir + "/printer.cfg", stock + block);
  const MachineProfile p = tunekit::machine::load_machine_profile(dir + "/printer.cfg");
  CHECK(p.state.shaper.at("x") == "mzv:48.6:0.1");
  CHECK(p.state.shaper.at("y") == "ei:39.2:0.1");
  CHECK(p.extruder.max_velocity_mm_s == 45);  // only in the block
  const std::size_t lines_before = static_cast<std::size_t>(std::count(stock.begin(), stock.end(), '\n'));
  CHECK(p.sources.at("extruder.max_velocity_mm_s") ==
        fmt::format("{}/printer.cfg:{} [extruder] max_extrude_only_velocity = 45", dir, lines_before + 7));
  // [extruder] max_temp: 250 above also sets it: Klipper's load drops the block's duplicate
  // (klippy/configfile.py ConfigAutoSave._strip_duplicates; SAVE_CONFIG itself comments the
  // regular one out when it writes the block).
  CHECK(p.temperature.hotend_max_c == 250);

  // A block whose header is not Klipper's exact AUTOSAVE_HEADER is not read by Klipper either.
  write(dir + "/loose.cfg", stock + "\n#*# <--- SAVE_CONFIG --->\n#*# [input_shaper]\n#*# shaper_freq_x = 48.6\n");
  CHECK(tunekit::machine::load_machine_profile(dir + "/loose.cfg").state.shaper.empty());
}

TEST_CASE("Klipper: hostile values and broken files give one located error", "[profiles][klipper][errors]") {
  const std::string stock = tunekit::test::read_text(klipper("printer-creality-ender3-v2-2020.cfg"));
  const std::string dir = tunekit::test::scratch_dir("klipper_hostile");
  const auto with = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string t = stock;
    const auto at = t.find(from);
    REQUIRE(at != std::string::npos);
    t.replace(at, from.size(), to);
    write(dir + "/" + name, t);
    return dir + "/" + name;
  };
  auto e = import_error(with("nan.cfg", "max_accel: 3000", "max_accel: nan"));
  CHECK(e.location() == dir + "/nan.cfg:93");
  CHECK(e.message() == "[printer] max_accel = 'nan' is not a number");
  e = import_error(with("inf.cfg", "max_velocity: 300", "max_velocity: inf"));
  CHECK(e.location() == dir + "/inf.cfg:92");
  CHECK_THAT(e.message(), Contains("'inf' is not a number"));
  e = import_error(with("huge.cfg", "max_accel: 3000", "max_accel: 1e308"));
  CHECK(e.location() == dir + "/huge.cfg:93");
  CHECK_THAT(e.message(), Contains("1e+308 is not a plausible acceleration"));
  e = import_error(with("negative.cfg", "position_max: 235", "position_max: -5"));
  CHECK_THAT(e.message(), Contains("position_max must be above position_min"));
  e = import_error(with("corexz.cfg", "kinematics: cartesian", "kinematics: corexz"));
  CHECK(e.location() == dir + "/corexz.cfg:91");
  CHECK_THAT(e.message(), Contains("'corexz' is not one tunekit supports"));
  e = import_error(with("noextruder.cfg", "[extruder]", "[extruder_disabled]"));
  CHECK_THAT(e.message(), Contains("no [extruder] section"));
  e = import_error(with("garbage.cfg", "max_accel: 3000", "max_accel 3000"));
  CHECK(e.location() == dir + "/garbage.cfg:93");
  CHECK_THAT(e.message(), Contains("neither a [section] nor an option"));

  write(dir + "/empty.cfg", "");
  const auto r = tunekit::machine::ProfileImportOptions{};
  try {
    (void)tunekit::machine::import_machine_profile(dir + "/empty.cfg", r);
    FAIL("an empty file imported");
  } catch (const tunekit::InputError& err) {
    CHECK(err.formatted() == "tunekit: error: " + dir + "/empty.cfg: the file is empty");
  }
}
