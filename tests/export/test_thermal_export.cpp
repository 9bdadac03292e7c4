// The hot end's thermal model exported as each firmware's temperature control: the values in the
// firmware's own names, units and syntax, and its bounds. Names, units and bounds were read in
// the firmware's source:
//   Marlin 2.1.3 (MarlinFirmware/Configurations import-2.1.x 25e9ab2318, 2024-10-13:
//     config/default/Configuration.h, "Model Predictive Control for hotend";
//     Marlin/src/gcode/temp/M306.cpp: P C R A F H, the report's decimals 2 2 4 4 4 4, F the loss
//     at full fan).
//   Kalico (KalicoCrew/kalico main f2532ee34, 2026-07-19: klippy/extras/heaters.py control "mpc":
//     heater_power, block_heat_capacity, sensor_responsiveness above=0., ambient_transfer minval=0.,
//     filament_heat_capacity above=0. in J/(g K) with filament_density 1.2 and filament_diameter
//     1.75 by default, fan_ambient_transfer getfloatlist; klippy/extras/control_mpc.py MPC_SET).
//   Klipper (Klipper3d/klipper 84104bbbd, 2026-08-07: klippy/extras/heaters.py PID_PARAM_BASE =
//     255., ControlPID reads pid_Kp, pid_Ki, pid_Kd and divides each by it).
//   RepRapFirmware 3.5 (Duet3D/RepRapFirmware 3.5-dev fc1cd16c, 2024-10-23: src/Heating/FOPDT.cpp
//     SetParameters bounds and AppendM307Command "M307 H%u R%.3f K%.3f:%.3f D%.2f E%.2f S%.2f B%d",
//     GetCoolingRate: K at 100 K rise, the fan's rate linear in the rise).
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/thermal_control.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/thermal_export.hpp"

using namespace tunekit;
using namespace tunekit::firmware;
using Catch::Matchers::Contains;
using tunekit::test::run_cli;
using tunekit::test::scratch_dir;

// The file's helpers in a namespace of their own: the test areas are unity builds.
namespace test_thermal_export {

/// A hot end like the one Marlin's default configuration describes, with other numbers so that
/// every written value differs from the file's.
ident::ThermalModel hot_end() {
  ident::ThermalModel m;
  m.heater_power_w = 42.5;
  m.block_heat_capacity_j_per_k = 18.42;
  m.sensor_responsiveness_per_s = 0.2176;
  m.ambient_transfer_w_per_k = 0.0664;
  m.fan_transfer_w_per_k = 0.0998;
  m.filament_heat_capacity_j_per_k_mm = 0.0036;  // 1.75 mm PETG (Marlin's Configuration.h note)
  return m;
}

CompensatorSettings thermal_only(const ident::ThermalModel& m = hot_end()) {
  CompensatorSettings s;
  ThermalExport t;
  t.model = m;
  s.thermal = t;
  return s;
}

bool has_line(const std::string& text, const std::string& line) {
  return ("\n" + text).find("\n" + line + "\n") != std::string::npos;
}

}  // namespace test_thermal_export

using namespace test_thermal_export;

TEST_CASE("Marlin MPC: Configuration.h's MPC defines and the M306 line carry the model") {
  const std::string path = dataset("marlin_configs/creality-ender3-v2/Configuration.h");
  const ExportResult r = export_config_file(ExportFirmware::marlin, path, thermal_only());
  // MPCTEMP on, PIDTEMP off: SanityCheck.h refuses both.
  CHECK(has_line(r.updated,
                 "#define MPCTEMP         // See https://marlinfw.org/docs/features/model_predictive_control.html"));
  CHECK(r.updated.find("\n//#define PIDTEMP ") != std::string::npos);
  CHECK(r.updated.find("\n#define PIDTEMP ") == std::string::npos);
  // The list form and f suffix of the file are kept; values at M306's report decimals.
  CHECK_THAT(r.updated, Contains("#define MPC_HEATER_POWER { 42.5f }"));
  CHECK_THAT(r.updated, Contains("#define MPC_BLOCK_HEAT_CAPACITY { 18.42f }"));
  CHECK_THAT(r.updated, Contains("#define MPC_SENSOR_RESPONSIVENESS { 0.2176f }"));
  CHECK_THAT(r.updated, Contains("#define MPC_AMBIENT_XFER_COEFF { 0.0664f }"));
  CHECK_THAT(r.updated, Contains("#define MPC_AMBIENT_XFER_COEFF_FAN255 { 0.0998f }"));
  CHECK_THAT(r.updated, Contains("#define FILAMENT_HEAT_CAPACITY_PERMM { 0.0036f }"));
  CHECK(r.gcode == "M306 E0 P42.5 C18.42 R0.2176 A0.0664 F0.0998 H0.0036\nM500\n");
  // All-or-nothing and idempotent: the edited file edits to itself.
  const ExportResult again = export_config_text(ExportFirmware::marlin, r.updated, path, thermal_only());
  CHECK_FALSE(again.changed());
}

TEST_CASE("Marlin MPC: a fan that warms the hot end, or Configuration_adv.h, is refused") {
  auto m = hot_end();
  m.fan_transfer_w_per_k = 0.05;  // below A
  CHECK_THROWS_WITH(export_config_file(ExportFirmware::marlin,
                                       dataset("marlin_configs/creality-ender3-v2/Configuration.h"), thermal_only(m)),
                    Contains("MPC_AMBIENT_XFER_COEFF_FAN255"));
  CHECK_THROWS_WITH(
      export_config_file(ExportFirmware::marlin, dataset("marlin_configs/creality-ender3-v2/Configuration_adv.h"),
                         thermal_only()),
      Contains("Configuration.h"));
  m = hot_end();
  m.sensor_responsiveness_per_s = 0.00004;  // written as 0 with 4 decimals
  CHECK_THROWS_WITH(export_config_file(ExportFirmware::marlin,
                                       dataset("marlin_configs/creality-ender3-v2/Configuration.h"), thermal_only(m)),
                    Contains("sensor responsiveness"));
}

TEST_CASE("Kalico MPC: control mpc and its keys in [extruder], the PID options commented out") {
  const std::string path = dataset("firmware/printer.cfg");
  const ExportResult r = export_config_file(ExportFirmware::kalico, path, thermal_only());
  // The SAVE_CONFIG block holds the heater's control: edited there (Klipper reads it there); the
  // keys no part of the file sets go into the body's [extruder].
  CHECK(has_line(r.updated, "#*# control = mpc"));
  CHECK(has_line(r.updated, "#*# #pid_kp = 26.213"));
  CHECK(has_line(r.updated, "#*# #pid_ki = 1.304"));
  CHECK(has_line(r.updated, "#*# #pid_kd = 131.721"));
  CHECK(has_line(r.updated, "heater_power: 42.5"));
  CHECK(has_line(r.updated, "block_heat_capacity: 18.42"));
  CHECK(has_line(r.updated, "sensor_responsiveness: 0.2176"));
  CHECK(has_line(r.updated, "ambient_transfer: 0.0664"));
  // Three breakpoints (0, 50, 100 %), Kalico's default, on the model's linear fan loss.
  CHECK(has_line(r.updated, "fan_ambient_transfer: 0.0664, 0.0831, 0.0998"));
  // H = 0.0036 J/(K mm) over 1.2e-3 g/mm^3 x pi 1.75^2/4 mm^2 = 2.8863e-3 g/mm: 1.2473 J/(g K).
  CHECK(has_line(r.updated, "filament_heat_capacity: 1.2473"));
  // The heater bed's PID is not touched.
  CHECK(has_line(r.updated, "#*# pid_kp = 54.027"));
  CHECK_THAT(
      r.gcode,
      Contains("MPC_SET HEATER=extruder BLOCK_HEAT_CAPACITY=18.42 SENSOR_RESPONSIVENESS=0.2176 "
               "AMBIENT_TRANSFER=0.0664 FAN_AMBIENT_TRANSFER=0.0664,0.0831,0.0998 FILAMENT_HEAT_CAPACITY=1.2473"));
  const ExportResult again = export_config_text(ExportFirmware::kalico, r.updated, path, thermal_only());
  CHECK_FALSE(again.changed());
}

TEST_CASE("Klipper PID: SIMC gains times 255 in pid_kp, pid_ki, pid_kd with 3 decimals") {
  const auto pid = design::design_thermal_pid(hot_end());
  const auto k = design::klipper_pid_gains(pid);
  // Klipper's heaters.py divides by PID_PARAM_BASE = 255.
  CHECK(k.kp == Approx(pid.kp_per_k * 255.0));
  const std::string path = dataset("firmware/printer.cfg");
  const ExportResult r = export_config_file(ExportFirmware::klipper, path, thermal_only());
  CHECK(has_line(r.updated, "#*# control = pid"));
  CHECK(has_line(r.updated, "#*# pid_kp = " + format_number(k.kp, 3)));
  CHECK(has_line(r.updated, "#*# pid_ki = " + format_number(k.ki, 3)));
  CHECK(has_line(r.updated, "#*# pid_kd = " + format_number(k.kd, 3)));
  CHECK(r.gcode.empty());  // Klipper has no command that sets PID gains at run time
  // Gains of the size PID_CALIBRATE finds on such hot ends (this file's own 26.2 / 1.30 / 132).
  CHECK(k.kp > 10);
  CHECK(k.kp < 60);
  CHECK(k.ki > 0.3);
  CHECK(k.ki < 3);
  CHECK(k.kd > 40);
  CHECK(k.kd < 300);
}

TEST_CASE("RepRapFirmware: M307 H1 R K off:on D E in config.g, S and B kept") {
  const std::string path = dataset("rrf_configs/ender3pro-x0r-maestro-rrf3/config.g");
  CompensatorSettings s = thermal_only();
  const ExportResult r = export_config_file(ExportFirmware::rrf, path, s);
  // R = P/C = 42.5/18.42 = 2.307 K/s; K = 100 A/C = 0.360, fan 100 (F-A)/C = 0.181 K/s at 100 K;
  // D = 1/R + 0.8 s = 5.40 s; E = 1.
  CHECK(has_line(r.updated,
                 "M307 H1 B0 S1.00 R2.307 K0.36:0.181 D5.4 E1                                   ; "
                 "disable bang-bang mode for heater  and set PWM limit"));
  CHECK(has_line(r.updated,
                 "M307 H0 B0 S1.00                                   ; disable bang-bang mode for the bed "
                 "heater and set PWM limit"));
  CHECK(r.gcode == "M307 H1 R2.307 K0.36:0.181 D5.4 E1\n");
}

TEST_CASE("RepRapFirmware: the model's bounds as FOPDT.cpp checks them") {
  const std::string path = dataset("rrf_configs/ender3pro-x0r-maestro-rrf3/config.g");
  auto m = hot_end();
  m.heater_power_w = 0.5;  // R/K = (0.5/18.42)/(6.64/18.42) < 0.1: "estimated temperature rise too small"
  CHECK_THROWS_WITH(export_config_file(ExportFirmware::rrf, path, thermal_only(m)),
                    Contains("estimated temperature rise too small"));
  m = hot_end();
  m.fan_transfer_w_per_k = 0.03;
  CHECK_THROWS_WITH(export_config_file(ExportFirmware::rrf, path, thermal_only(m)),
                    Contains("fan reduces cooling rate"));
  m = hot_end();
  m.sensor_responsiveness_per_s = 0.005;  // D = 200.8 s, D K = 72 > 50
  CHECK_THROWS_WITH(export_config_file(ExportFirmware::rrf, path, thermal_only(m)),
                    Contains("dead time too close to cooling time constant"));
  // Exponent 1.35 matches the loss at 180 K above ambient: K (1.8)^1.35 = (A/C) 180.
  const auto e = design::rrf_heater_model(hot_end(), 1.35, 180.0);
  CHECK(e.cooling_rate_k_s * std::pow(1.8, 1.35) == Approx(0.0664 / 18.42 * 180.0));
  CHECK_THROWS_AS(design::rrf_heater_model(hot_end(), 1.7), InputError);
}

TEST_CASE("RepRapFirmware: a config.g that creates no such heater is refused with the reason") {
  auto s = thermal_only();
  s.thermal->rrf_heater = 3;
  CHECK_THROWS_WITH(
      export_config_file(ExportFirmware::rrf, dataset("rrf_configs/ender3pro-x0r-maestro-rrf3/config.g"), s),
      Contains("no 'M950 H3' line"));
}

TEST_CASE("The SIMC PID states its margins, computed on the loop it closes") {
  const auto pid = design::design_thermal_pid(hot_end());
  CHECK_THAT(pid.rule, Contains("SIMC"));
  // Series SIMC with tau_c = 1/R: Kc = tau1/(k (tau_c + theta)), tau_I = min(tau1, 4(tau_c + theta)).
  const double tau1 = 18.42 / 0.0664, k = 42.5 / 0.0664, tau2 = 1 / 0.2176, theta = 0.8;
  const double kc = tau1 / (k * (tau2 + theta)), ti = std::min(tau1, 4 * (tau2 + theta));
  CHECK(pid.kp_per_k == Approx(kc * (1 + tau2 / ti)));
  CHECK(pid.ki_per_k_s == Approx(kc / ti));
  CHECK(pid.kd_s_per_k == Approx(kc * tau2));
  // A robust loop: Ms below 2 (SIMC's tight setting gives about 1.6-1.7; this one is slower), a
  // gain margin above 2 and a phase margin above 45 degrees.
  CHECK(pid.max_sensitivity > 1.0);
  CHECK(pid.max_sensitivity < 2.0);
  CHECK(pid.gain_margin > 2.0);
  CHECK(pid.phase_margin_deg > 45.0);
  // The tight setting tau_c = theta is faster and less robust: the margins must show it.
  design::ThermalPidOptions tight;
  tight.closed_loop_time_s = 0.8;
  const auto fast = design::design_thermal_pid(hot_end(), tight);
  CHECK(fast.kp_per_k > pid.kp_per_k);
  CHECK(fast.max_sensitivity > pid.max_sensitivity);
  CHECK(fast.gain_margin < pid.gain_margin);
}

TEST_CASE("tunekit export reads the results of tunekit thermal and refuses a model it cannot write") {
  const std::string dir = scratch_dir("thermal_export_cli");
  const std::string cfg = dir + "/printer.cfg";
  const std::string original = "[extruder]\nheater_pin: PA2\ncontrol: watermark\nmax_delta: 2.0\n";
  std::ofstream(cfg) << original;
  nlohmann::json results = {{"command", "thermal"},
                            {"results",
                             {{"thermal_model",
                               {{"heater_power_w", 42.5},
                                {"block_heat_capacity_j_per_k", {{"value", 18.42}, {"ci95", {18.0, 18.9}}}},
                                {"sensor_responsiveness_per_s", 0.2176},
                                {"ambient_transfer_w_per_k", 0.0664},
                                {"fan_transfer_w_per_k", 0.0998}}}}}};
  const std::string good = dir + "/thermal.json";
  std::ofstream(good) << results.dump(2);
  const auto r = run_cli({"export", "-f", "klipper", "-c", cfg, good, "--write"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string written = tunekit::test::read_text(cfg);
  const auto k = design::klipper_pid_gains(design::design_thermal_pid(hot_end()));
  CHECK(has_line(written, "control: pid"));
  CHECK(has_line(written, "#max_delta: 2.0"));
  CHECK(has_line(written, "pid_kp: " + format_number(k.kp, 3)));

  results["results"]["thermal_model"]["sensor_responsiveness_per_s"] = -0.2;
  const std::string bad = dir + "/bad.json";
  std::ofstream(bad) << results.dump(2);
  std::ofstream(cfg) << original;
  const auto refused = run_cli({"export", "-f", "klipper", "-c", cfg, bad, "--write"});
  CHECK(refused.code == 2);
  CHECK_THAT(refused.err, Contains("sensor responsiveness"));
  CHECK(tunekit::test::read_text(cfg) == original);
  const auto garbled = run_cli({"export", "-f", "rrf", "-c", cfg, "--thermal-model", "40:16.7:x:0.07:0.09"});
  CHECK(garbled.code == 2);
  CHECK_THAT(garbled.err, Contains("--thermal-model takes P:C:R:A:F[:H]"));
  // A finite value no hot end has (a typing error, a failed fit) never reaches the file either.
  for (const char* model : {"1e308:16.7:0.22:0.07:0.09", "40:16.7:0.22:0.07:1e300", "40:1e9:0.22:0.07:0.09"}) {
    INFO(model);
    const auto huge = run_cli({"export", "-f", "klipper", "-c", cfg, "--thermal-model", model, "--write"});
    CHECK(huge.code == 2);
    CHECK_THAT(huge.err, Contains("any hot end's"));
    CHECK(tunekit::test::read_text(cfg) == original);
  }
}
