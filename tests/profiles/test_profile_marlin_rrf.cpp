// Machine profiles from a real Marlin Configuration.h (MarlinFirmware's Ender-3 V2 example,
// datasets/marlin_configs) and two real RepRapFirmware config.g files (Duet3D's collection of
// users' machine configurations, datasets/rrf_configs): the limits each firmware sets from the
// file, value by value, hand checked against the file and the firmware's source (Marlin:
// planner.cpp, temperature.h; RepRapFirmware: GCodes2.cpp M350, Configuration.h defaults). An
// M503 report written for this test checks the report reader and the one error for what a
// report does not hold.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/profile_import.hpp"

using Catch::Matchers::Contains;
using tunekit::machine::MachineProfile;
using tunekit::test::dataset;

TEST_CASE("Marlin: the Ender-3 V2's Configuration.h gives the limits Marlin sets", "[profiles][marlin]") {
  const std::string path = dataset("marlin_configs/creality-ender3-v2/Configuration.h");
  const MachineProfile p = tunekit::machine::load_machine_profile(path);
  CHECK(p.firmware == "marlin");
  CHECK(p.kinematics == "cartesian");
  // X_BED_SIZE 220, X_MIN_POS 0, X_MAX_POS X_BED_SIZE (an expression of another define), Z_MAX_POS 250.
  CHECK(p.axis("x").min_mm == 0);
  CHECK(p.axis("x").max_mm == 220);
  CHECK(p.axis("y").max_mm == 220);
  CHECK(p.axis("z").max_mm == 250);
  // DEFAULT_MAX_FEEDRATE { 500, 500, 5, 25 } mm/s, DEFAULT_MAX_ACCELERATION { 500, 500, 100, 1000 }.
  CHECK(p.axis("x").max_velocity_mm_s == 500);
  CHECK(p.axis("z").max_velocity_mm_s == 5);
  CHECK(p.axis("x").max_accel_mm_s2 == 500);
  CHECK(p.axis("z").max_accel_mm_s2 == 100);
  CHECK(p.extruder.max_velocity_mm_s == 25);
  // Extrude-only moves run at DEFAULT_RETRACT_ACCELERATION 500 (planner.cpp), below M201 E 1000.
  CHECK(p.extruder.max_accel_mm_s2 == 500);
  CHECK(p.state.retract_accel_mm_s2 == 500);
  CHECK(p.state.max_accel_e_mm_s2 == 1000);
  CHECK(p.print.max_accel_mm_s2 == 500);  // DEFAULT_ACCELERATION
  // HEATER_0_MAXTEMP 275 - HOTEND_OVERSHOOT 15; BED_MAXTEMP 120 - BED_OVERSHOOT 10 (temperature.h).
  CHECK(p.temperature.hotend_max_c == 260);
  CHECK(p.temperature.bed_max_c == 110);
  CHECK(p.extruder.filament_diameter_mm == 1.75);          // DEFAULT_NOMINAL_FILAMENT_DIA
  CHECK(p.extruder.max_extrude_only_distance_mm == 1000);  // PREVENT_LENGTHY_EXTRUDE, EXTRUDE_MAXLENGTH 1000
  CHECK(p.state.steps_per_mm_x == 80);                     // DEFAULT_AXIS_STEPS_PER_UNIT { 80, 80, 400, 93 }
  CHECK(p.state.min_segment_time_s == Approx(0.020));      // Configuration_adv.h DEFAULT_MINSEGMENTTIME 20000 us
  CHECK(p.state.shaper.empty());                           // //#define INPUT_SHAPING_X: off
  CHECK(p.sources.at("axes.x.max_velocity_mm_s") ==
        path + ":1303 #define DEFAULT_MAX_FEEDRATE          { 500, 500, 5, 25 }");
  CHECK_THAT(p.sources.at("extruder.max_accel_mm_s2"), Contains("planner.cpp") && Contains("M204 R"));
  CHECK_THAT(p.sources.at("temperature.hotend_max_c"), Contains("HEATER_0_MAXTEMP 275 - HOTEND_OVERSHOOT 15 = 260"));
  CHECK_THAT(p.sources.at("extruder.nozzle_diameter_mm"), Contains("tunekit default"));
  const auto back = tunekit::machine::parse_machine_profile(tunekit::machine::machine_profile_toml(p), "back.toml");
  CHECK(back.axis("x").max_mm == 220);
  CHECK(back.extruder.max_accel_mm_s2 == 500);
  CHECK(back.state.retract_accel_mm_s2 == 500);
}

TEST_CASE("Marlin: the Anycubic Kossel Linear Plus's delta Configuration.h, its #if branches followed",
          "[profiles][marlin][delta]") {
  const std::string path = dataset("marlin_configs/anycubic-kossel-linear-plus/Configuration.h");
  const MachineProfile p = tunekit::machine::load_machine_profile(path);
  CHECK(p.kinematics == "delta");  // #define DELTA
  // #if ENABLED(ANYCUBIC_KOSSEL_PLUS): PRINTABLE_RADIUS 120.0 (the #else branch has 90, a POLAR
  // block 82); tunekit's box is the square inside the circle: +-120 / sqrt(2) = +-84.853 mm.
  CHECK(p.axis("x").max_mm == Approx(84.85281).epsilon(1e-6));
  CHECK(p.axis("y").min_mm == Approx(-84.85281).epsilon(1e-6));
  // Z_MAX_POS MANUAL_Z_HOME_POS, MANUAL_Z_HOME_POS DELTA_HEIGHT, DELTA_HEIGHT 300.00.
  CHECK(p.axis("z").min_mm == 0);
  CHECK(p.axis("z").max_mm == 300);
  CHECK(p.axis("x").max_velocity_mm_s == 100);  // DEFAULT_MAX_FEEDRATE { 100, 100, 100, 100}
  CHECK(p.axis("x").max_accel_mm_s2 == 3000);
  CHECK(p.print.max_accel_mm_s2 == 600);
  CHECK(p.extruder.max_accel_mm_s2 == 3000);  // M204 R 3000 = M201 E 3000
  // DEFAULT_XYZ_STEPS_PER_UNIT ((200) * (16) / double(2) / double(20)) = 80.
  CHECK(p.state.steps_per_mm_x == 80);
  CHECK(p.extruder.max_extrude_only_distance_mm == 750);
  CHECK(p.temperature.hotend_max_c == 260);  // 275 - 15
  CHECK(p.temperature.bed_max_c == 110);     // 120 - 10

  // The normal-size Kossel: the #else branch's PRINTABLE_RADIUS 90.0.
  std::string t = tunekit::test::read_text(path);
  t.replace(t.find("#define ANYCUBIC_KOSSEL_PLUS"), 28, "//#define ANYCUBIC_KOSSEL_PLUS");
  const std::string dir = tunekit::test::scratch_dir("marlin_kossel_normal");
  std::ofstream(dir + "/Configuration.h", std::ios::binary) << t;
  const MachineProfile n = tunekit::machine::load_machine_profile(dir + "/Configuration.h");
  CHECK(n.axis("x").max_mm == Approx(90 / std::sqrt(2.0)));
}

TEST_CASE("RepRapFirmware: an Ender-3 Pro's config.g gives the limits the firmware sets", "[profiles][rrf]") {
  const std::string path = dataset("rrf_configs/ender3pro-x0r-maestro-rrf3/config.g");
  const MachineProfile p = tunekit::machine::load_machine_profile(path);
  CHECK(p.firmware == "rrf");
  CHECK(p.kinematics == "cartesian");
  // M208 X0 Y0 Z-0.5 S1 / M208 X235 Y235 Z228 S0.
  CHECK(p.axis("x").min_mm == 0);
  CHECK(p.axis("x").max_mm == 235);
  CHECK(p.axis("z").min_mm == -0.5);
  CHECK(p.axis("z").max_mm == 228);
  // M203 X12000 Y12000 Z900 E6000 mm/min -> 200, 15, 100 mm/s; M201 X6000 Y6000 Z200 E5000.
  CHECK(p.axis("x").max_velocity_mm_s == Approx(200));
  CHECK(p.axis("z").max_velocity_mm_s == Approx(15));
  CHECK(p.axis("x").max_accel_mm_s2 == 6000);
  CHECK(p.axis("z").max_accel_mm_s2 == 200);
  CHECK(p.extruder.max_velocity_mm_s == Approx(100));
  CHECK(p.extruder.max_accel_mm_s2 == 5000);
  CHECK(p.print.max_accel_mm_s2 == 600);  // M204 P600
  // M143 H1 S240 (tool 0's heater: M563 P0 ... H1); M143 H0 S150 (the bed: M140 H0).
  CHECK(p.temperature.hotend_max_c == 240);
  CHECK(p.temperature.bed_max_c == 150);
  // M350 X16 ..., M92 X80 ... E97, then M350 X32 Y32 E128: RepRapFirmware rescales steps/mm
  // (GCodes::ChangeMicrostepping): X 80 * 32/16 = 160, E 97 * 128/16 = 776 (as the file's comment says).
  CHECK(p.state.steps_per_mm_x == 160);
  CHECK(p.state.steps_per_mm_y == 160);
  CHECK(p.state.jerk_xy_mm_s == Approx(800.0 / 60));  // M566 X800 mm/min
  CHECK_THAT(p.sources.at("firmware_state.steps_per_mm_x"), Contains("ChangeMicrostepping"));
  CHECK_THAT(p.sources.at("axes.x.max_velocity_mm_s"), Contains("config.g:26 M203 X12000") && Contains("/ 60"));
}

TEST_CASE("RepRapFirmware: a Prusa MK3S's config.g (M208 min:max, no M204) gives the firmware's limits",
          "[profiles][rrf]") {
  const MachineProfile p = tunekit::machine::load_machine_profile(dataset("rrf_configs/prusa-mk3s/config.g"));
  // M208 X0:250 Y-4:215 Z-0.1:205.
  CHECK(p.axis("x").min_mm == 0);
  CHECK(p.axis("x").max_mm == 250);
  CHECK(p.axis("y").min_mm == -4);
  CHECK(p.axis("y").max_mm == 215);
  CHECK(p.axis("z").min_mm == -0.1);
  CHECK(p.axis("z").max_mm == 205);
  // M203 X12000 Z750 E1500 mm/min; M201 X2500 Y2500 Z1000 E5000.
  CHECK(p.axis("x").max_velocity_mm_s == Approx(200));
  CHECK(p.axis("z").max_velocity_mm_s == Approx(12.5));
  CHECK(p.extruder.max_velocity_mm_s == Approx(25));
  CHECK(p.extruder.max_accel_mm_s2 == 5000);
  // No M204: RepRapFirmware's default print acceleration is above any M201 limit, so M201 X/Y rule.
  CHECK(p.print.max_accel_mm_s2 == 2500);
  CHECK(p.temperature.hotend_max_c == 285);  // M143 H1 S285
  CHECK(p.temperature.bed_max_c == 120);     // M143 H0 S120
  CHECK(p.state.steps_per_mm_x == 200);      // M92 X200.00 at x16
}

TEST_CASE("RepRapFirmware: a Kossel delta's config.g (M665, no M208, no M143) gives the firmware's limits",
          "[profiles][rrf][delta]") {
  const MachineProfile p =
      tunekit::machine::load_machine_profile(dataset("rrf_configs/kossel-dc42-smart-effector/config.g"));
  CHECK(p.kinematics == "delta");  // M665 L361.676 R180.679 H470.070 B150.0
  // Printable radius B 150 mm: the box inside the circle, +-150 / sqrt(2) = +-106.066 mm; Z from the
  // firmware's default minimum 0 to the homed height H 470.07 mm.
  CHECK(p.axis("x").max_mm == Approx(106.06602).epsilon(1e-6));
  CHECK(p.axis("y").min_mm == Approx(-106.06602).epsilon(1e-6));
  CHECK(p.axis("z").min_mm == 0);
  CHECK(p.axis("z").max_mm == Approx(470.07));
  CHECK(p.axis("x").max_velocity_mm_s == Approx(250));  // M203 X15000 mm/min
  CHECK(p.axis("z").max_accel_mm_s2 == 3000);           // M201 Z3000
  CHECK(p.extruder.max_velocity_mm_s == Approx(60));    // M203 E3600 mm/min
  CHECK(p.extruder.max_accel_mm_s2 == 1000);            // M201 E1000
  CHECK(p.print.max_accel_mm_s2 == 3000);               // no M204: M201 X/Y
  // No M143: RepRapFirmware's default limits (285 degC, the lower of the versions' hot-end
  // defaults; 125 degC for the bed).
  CHECK(p.temperature.hotend_max_c == 285);
  CHECK(p.temperature.bed_max_c == 125);
  CHECK(p.state.shaper.empty());  // M593 F0: off
}

TEST_CASE("Marlin: an M503 report is read, and what it lacks is named in one error", "[profiles][marlin][m503]") {
  // Written for this test in the layout Marlin 2.1 prints (Marlin/src/module/settings.cpp), with
  // the OctoPrint terminal's "Recv: " prefix on some lines.
  const std::string report =
      "echo:; Steps per unit:\n"
      "echo:  M92 X80.00 Y80.00 Z400.00 E93.00\n"
      "echo:; Max feedrates (units/s):\n"
      "Recv: echo:  M203 X500.00 Y500.00 Z5.00 E25.00\n"
      "echo:; Max Acceleration (units/s2):\n"
      "echo:  M201 X500.00 Y500.00 Z100.00 E5000.00\n"
      "echo:; Acceleration (units/s2) (P<print-accel> R<retract-accel> T<travel-accel>):\n"
      "echo:  M204 P500.00 R1000.00 T1000.00\n"
      "echo:  M205 B20000.00 S0.00 T0.00 J0.08\n"
      "echo:  M200 S0 D1.75\n"
      "echo:  M593 X F40.00 D0.15\n"
      "echo:  M593 Y F42.50 D0.10\n";
  const std::string path = tunekit::test::write_scratch("m503_report.txt", report);
  try {
    (void)tunekit::machine::load_machine_profile(path);
    FAIL("an M503 report without travel was imported");
  } catch (const tunekit::InputError& e) {
    CHECK(e.location() == path);
    CHECK_THAT(e.message(), Contains("holds no travel") && Contains("--travel X,Y,Z") && Contains("--hotend-max-c") &&
                                Contains("--bed-max-c"));
  }
  tunekit::machine::ProfileImportOptions o;
  o.travel_mm = {220, 220, 250};
  o.hotend_max_c = 260;
  o.bed_max_c = 110;
  const MachineProfile p = tunekit::machine::import_machine_profile(path, o);
  CHECK(p.axis("x").max_mm == 220);
  CHECK(p.axis("x").max_velocity_mm_s == 500);
  CHECK(p.extruder.max_velocity_mm_s == 25);
  CHECK(p.extruder.max_accel_mm_s2 == 1000);  // M204 R1000, below M201 E5000
  CHECK(p.print.max_accel_mm_s2 == 500);
  CHECK(p.state.shaper.at("x") == "zv:40:0.15");
  CHECK(p.state.shaper.at("y") == "zv:42.5:0.1");
  CHECK(p.sources.at("axes.x.max_velocity_mm_s") == path + ":4 M203 X500.00 Y500.00 Z5.00 E25.00");
  CHECK(p.sources.at("axes.x.max_mm") == "given on the command line (--travel)");
}

TEST_CASE("Marlin: a real Ender 5's M503 report gives the limits Marlin applies", "[profiles][marlin][m503]") {
  // A user's Ender 5 (Marlin bugfix-2.1.x, Creality v4.2.7 board), datasets/marlin_configs; the
  // report holds no travel and no heater limits: the Ender 5's 220 x 220 x 300 mm and Marlin's
  // stock HEATER_0_MAXTEMP 275 - HOTEND_OVERSHOOT 15 and BED_MAXTEMP 125 - BED_OVERSHOOT 10.
  const std::string path = tunekit::test::dataset("marlin_configs/creality-ender5-m503/m503.txt");
  tunekit::machine::ProfileImportOptions o;
  o.travel_mm = {220, 220, 300};
  o.hotend_max_c = 260;
  o.bed_max_c = 115;
  const MachineProfile p = tunekit::machine::import_machine_profile(path, o);
  CHECK(p.firmware == "marlin");
  for (const char* a : {"x", "y"}) {
    CHECK(p.axis(a).max_velocity_mm_s == 500);  // M203 X500 Y500
    CHECK(p.axis(a).max_accel_mm_s2 == 500);    // M201 X500 Y500
  }
  CHECK(p.axis("z").max_velocity_mm_s == 5);
  CHECK(p.axis("z").max_accel_mm_s2 == 100);
  CHECK(p.axis("z").max_mm == 300);
  CHECK(p.extruder.max_velocity_mm_s == 25);  // M203 E25
  // Extrude-only moves: M204 R500, below M201 E5000 (planner.cpp: the retract acceleration).
  CHECK(p.extruder.max_accel_mm_s2 == 500);
  CHECK(p.print.max_accel_mm_s2 == 500);  // M204 P500
  CHECK(p.state.steps_per_mm_x == 80);
  CHECK(p.state.steps_per_mm_y == 80);
  CHECK(p.state.min_segment_time_s == Approx(0.02));  // M205 B20000 (us)
  CHECK(p.sources.at("axes.x.max_accel_mm_s2").find(":14 M201 X500.00 Y500.00 Z100.00 E5000.00") != std::string::npos);
  CHECK(p.temperature.hotend_max_c == 260);
}

TEST_CASE("Marlin and RepRapFirmware: hostile values give one located error", "[profiles][errors]") {
  const std::string dir = tunekit::test::scratch_dir("marlin_rrf_hostile");
  const auto copy_with = [&](const std::string& from, const std::string& name, const std::string& a,
                             const std::string& b) {
    std::string t = tunekit::test::read_text(dataset(from));
    const auto at = t.find(a);
    REQUIRE(at != std::string::npos);
    t.replace(at, a.size(), b);
    std::filesystem::create_directories(std::filesystem::path(dir + "/" + name).parent_path());
    std::ofstream(dir + "/" + name, std::ios::binary) << t;
    return dir + "/" + name;
  };
  auto expect = [](const std::string& path, const std::string& location, const std::string& text) {
    try {
      (void)tunekit::machine::load_machine_profile(path);
      FAIL("imported: " << path);
    } catch (const tunekit::InputError& e) {
      CHECK(e.location() == location);
      CHECK_THAT(e.message(), Contains(text));
    }
  };
  auto p = copy_with("rrf_configs/prusa-mk3s/config.g", "rrf_nan/config.g", "M201 X2500.00", "M201 Xnan");
  expect(p, p + ":27", "M201 X = 'nan' is not a number");
  p = copy_with("rrf_configs/prusa-mk3s/config.g", "rrf_huge/config.g", "M201 X2500.00", "M201 X1e308");
  expect(p, p + ":27", "is not a plausible acceleration");
  p = copy_with("rrf_configs/prusa-mk3s/config.g", "rrf_scara/config.g", "M584 X0", "M669 K4\nM584 X0");
  expect(p, p + ":33", "M669 K4: kinematics not one tunekit supports");
  p = copy_with("marlin_configs/creality-ender3-v2/Configuration.h", "marlin_inf/Configuration.h",
                "#define X_BED_SIZE 220", "#define X_BED_SIZE inf");
  expect(p, p + ":1881", "cannot evaluate 'inf'");
  p = copy_with("marlin_configs/creality-ender3-v2/Configuration.h", "marlin_huge/Configuration.h",
                "{ 500, 500, 100, 1000 }", "{ 1e308, 500, 100, 1000 }");
  expect(p, p + ":1316", "is not a plausible acceleration");
  p = copy_with("marlin_configs/creality-ender3-v2/Configuration.h", "marlin_deep/Configuration.h",
                "#define X_BED_SIZE 220", "#define X_BED_SIZE " + std::string(100000, '(') + "220");
  expect(p, p + ":1881", "cannot evaluate");  // nesting is bounded, not a stack overflow
}
