// Compensator design (advance K, smoothing window, flow dependence, dead time) and the
// `tunekit export` command end to end on fixtures of the step/freq/shaper/rheo envelopes.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "test_support.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/machine/machine_profile.hpp"

using namespace tunekit;
using Catch::Detail::Approx;

namespace {

std::string fixture(const std::string& name) { return tunekit::test::dataset("../tests/export/fixtures/" + name); }

design::AdvanceInputs sim_inputs() {
  const auto prof = machine::load_machine_profile(tunekit::test::dataset("machines/sim.toml"));
  design::AdvanceInputs in;
  in.filament_area_mm2 = prof.filament_area_mm2();
  in.line_area_mm2 = prof.line_area_mm2();
  in.print_speed_mm_s = prof.print.speed_mm_s;
  in.print_accel_mm_s2 = prof.print.max_accel_mm_s2;
  in.extruder_accel_limit_mm_s2 = prof.extruder.max_accel_mm_s2;
  return in;
}

}  // namespace

TEST_CASE("Smoothing window: the shortest T that keeps the extra extruder acceleration at the limit") {
  const double k = 0.05, a = 3000, r = 0.09 / (std::numbers::pi / 4 * 1.75 * 1.75), lim = 5000;
  const double t_box = design::min_smoothing_window_s(k, a, r, lim, design::SmoothingKernel::box);
  // The defining property: at T the extra acceleration K*a*r/T equals the limit; longer
  // windows stay below it, shorter ones exceed it.
  CHECK(k * a * r / t_box == Approx(lim));
  CHECK(k * a * r / (1.01 * t_box) < lim);
  CHECK(k * a * r / (0.99 * t_box) > lim);
  // Klipper's triangular weighting peaks at 2/T: twice the window for the same bound.
  CHECK(design::min_smoothing_window_s(k, a, r, lim, design::SmoothingKernel::triangular) == Approx(2 * t_box));
  // Twice the advance or twice the acceleration needs twice the window.
  CHECK(design::min_smoothing_window_s(2 * k, a, r, lim) == Approx(2 * t_box));
  CHECK(design::min_smoothing_window_s(k, 2 * a, r, lim) == Approx(2 * t_box));
  CHECK_THROWS_AS(design::min_smoothing_window_s(k, a, r, 0), InputError);
  CHECK_THROWS_AS(design::min_smoothing_window_s(-k, a, r, lim), InputError);
}

TEST_CASE("Advance design: K = tau, dead time reported, window from the machine profile") {
  auto in = sim_inputs();
  in.tau_s = 0.045;
  in.theta_s = 0.03;
  in.gain = 0.95;
  const auto d = design::design_advance(in);
  CHECK(d.k_s == Approx(0.045));
  CHECK(d.area_ratio == Approx(in.line_area_mm2 / in.filament_area_mm2));
  CHECK(d.design_flow_mm3_s == Approx(in.print_speed_mm_s * in.line_area_mm2));
  CHECK(d.window_box_s * in.extruder_accel_limit_mm_s2 == Approx(d.k_s * in.print_accel_mm_s2 * d.area_ratio));
  CHECK(d.theta_track_mm == Approx(0.03 * in.print_speed_mm_s));
  bool theta_note = false;
  for (const auto& n : d.notes) theta_note |= n.find("not cancelled") != std::string::npos;
  CHECK(theta_note);
  // What each firmware takes: rounded up, never below the bound.
  const auto klipper = firmware::smoothing_time_for(firmware::ExportFirmware::klipper, d);
  const auto marlin = firmware::smoothing_time_for(firmware::ExportFirmware::marlin, d);
  REQUIRE(klipper);
  REQUIRE(marlin);
  CHECK(*klipper >= d.window_triangular_s);
  // Klipper's default unless the bound is longer.
  CHECK(*klipper <= std::max(firmware::limits::kKlipperSmoothTimeDefault_s, d.window_triangular_s + 1e-4));
  CHECK(*klipper >= firmware::limits::kKlipperSmoothTimeDefault_s);
  CHECK(*marlin >= d.window_box_s);
  CHECK_FALSE(firmware::smoothing_time_for(firmware::ExportFirmware::rrf, d));
}

TEST_CASE("Flow-dependent advance from operating points and from a rheology prediction") {
  auto in = sim_inputs();
  const double af = in.filament_area_mm2;
  in.points = {{1.0, 0.96, 0.06, 0.035}, {4.0, 0.93, 0.03, 0.025}, {2.0, 0.95, 0.04, 0.03}};
  in.design_flow_mm3_s = 3.0 * af;  // halfway between the 2 and 4 mm/s feed points
  auto d = design::design_advance(in);
  CHECK(d.k_source == "operating points");
  // K(Q) = V(Q)/Q, V the integral of tau (held at 0.06 s below the first point, linear between):
  // V(3 af) = af (0.06 + (0.06 + 0.04)/2 + (0.04 + 0.035)/2) = 0.1475 af.
  CHECK(d.k_s == Approx(0.1475 / 3));
  CHECK(d.theta_s == Approx(0.0275));
  REQUIRE(d.schedule.size() == 3);
  CHECK(d.schedule[0].flow_mm3_s == Approx(1.0 * af));
  CHECK(d.schedule[0].k_s == Approx(0.06));
  CHECK(d.schedule[2].k_s == Approx(0.18 / 4));  // V(4 af) = af (0.06 + 0.05 + 0.07)
  // A single number is wrong by (0.06 - K) / 0.06 at the lowest flow.
  CHECK(d.single_k_max_rel_error == Approx((0.06 - 0.1475 / 3) / 0.06));
  CHECK(d.trend_k1_s_per_mm3_s < 0);

  design::AdvanceInputs rh = sim_inputs();
  rh.tau_s = 0.05;
  rh.rheo_flow_mm3_s = {1, 2, 4, 8};
  rh.rheo_relative_tau = {1.25, 1.0, 0.8, 0.64};
  rh.rheo_reference_flow_mm3_s = 2;
  rh.design_flow_mm3_s = 4;
  d = design::design_advance(rh);
  CHECK(d.k_source == "rheology");
  CHECK(d.k_s == Approx(0.05 * 0.8));
  CHECK(d.schedule.front().k_s == Approx(0.05 * 1.25));

  design::AdvanceInputs none = sim_inputs();
  CHECK_THROWS_AS(design::design_advance(none), InputError);
}

TEST_CASE("tunekit export: preview by default, --write applies with a backup, a second run changes nothing") {
  const std::string dir = tunekit::test::scratch_dir("export_cli");
  const std::string cfg = dir + "/printer.cfg";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/printer.cfg"), cfg);
  const std::string before = tunekit::test::read_text(cfg);
  const std::vector<std::string> base = {"export",
                                         "--firmware",
                                         "klipper",
                                         "--config",
                                         cfg,
                                         "--profile",
                                         tunekit::test::dataset("machines/sim.toml"),
                                         fixture("step.json"),
                                         fixture("shaper.json"),
                                         fixture("freq.json")};

  const auto preview = tunekit::test::run_cli(base);
  INFO(preview.err);
  REQUIRE(preview.code == 0);
  CHECK(tunekit::test::read_text(cfg) == before);  // preview writes nothing
  // An absolute path is named as it is (no a/ prefix doubling its slash).
  CHECK(preview.out.rfind("--- " + cfg + "\n+++ " + cfg + "\n", 0) == 0);
  CHECK(preview.out.find("+#*# shaper_freq_x = 52.4") != std::string::npos);
  CHECK(preview.out.find("+#*# shaper_type_y = ei") != std::string::npos);
  CHECK(preview.err.find("--write") != std::string::npos);

  // The design the command used, recomputed here from the fixture's operating points.
  auto in = sim_inputs();
  in.points = {{1.0, 0.96, 0.06, 0.035}, {2.0, 0.95, 0.04, 0.03}, {4.0, 0.93, 0.03, 0.025}};
  in.tau_s = 0.045;
  const auto d = design::design_advance(in);
  const auto smooth = firmware::smoothing_time_for(firmware::ExportFirmware::klipper, d);
  REQUIRE(smooth);
  const std::string k_line = "pressure_advance: " + firmware::format_number(d.k_s, 4) + "   ;";
  CHECK(preview.out.find("+" + k_line) != std::string::npos);
  CHECK(preview.out.find("+pressure_advance_smooth_time: " + firmware::format_number(*smooth, 4) + "\n") !=
        std::string::npos);

  auto args = base;
  args.push_back("--write");
  const auto written = tunekit::test::run_cli(args);
  REQUIRE(written.code == 0);
  const std::string after = tunekit::test::read_text(cfg);
  CHECK(after != before);
  CHECK(after.find(k_line) != std::string::npos);
  int backups = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".bak") {
      ++backups;
      CHECK(tunekit::test::read_text(e.path().string()) == before);
    }
  CHECK(backups == 1);

  const auto again = tunekit::test::run_cli(args);
  CHECK(again.code == 0);
  CHECK(again.out.empty());
  CHECK(again.err.find("nothing to change") != std::string::npos);
  CHECK(tunekit::test::read_text(cfg) == after);
  backups = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) backups += e.path().extension() == ".bak";
  CHECK(backups == 1);
}

TEST_CASE("tunekit export --json: deterministic envelope with settings, design, changes and G-code") {
  const std::string dir = tunekit::test::scratch_dir("export_json");
  const std::string cfg = dir + "/Configuration_adv.h";
  std::filesystem::copy_file(tunekit::test::dataset("firmware/Configuration_adv.h"), cfg);
  const std::vector<std::string> args = {"export",
                                         "-f",
                                         "marlin",
                                         "-c",
                                         cfg,
                                         "-p",
                                         tunekit::test::dataset("machines/sim.toml"),
                                         fixture("step.json"),
                                         fixture("shaper_zv.json"),
                                         fixture("rheo.json"),
                                         "--json"};
  const auto a = tunekit::test::run_cli(args);
  INFO(a.err);
  REQUIRE(a.code == 0);
  const auto b = tunekit::test::run_cli(args);
  CHECK(a.out == b.out);
  const auto j = nlohmann::json::parse(a.out);
  CHECK(j["command"] == "export");
  const auto& res = j["results"];
  CHECK(res["settings"]["shapers"]["x"]["firmware_type"] == "zv");
  CHECK(res["settings"]["shapers"]["y"]["freq_hz"].get<double>() == Approx(41.5));
  CHECK_FALSE(res["settings"]["shapers"].contains("z"));  // z is reported, not exported (Klipper only)
  CHECK(res["design"]["K_source"] == "operating points");
  CHECK(res["design"]["schedule"].size() == 3);
  CHECK(res["export"]["changed"] == true);
  CHECK(res["written"] == false);
  const std::string gcode = res["export"]["gcode"];
  CHECK(gcode.rfind("M900 K", 0) == 0);
  CHECK(gcode.find("M593 X F44 D0.1\n") != std::string::npos);
  CHECK(gcode.find("M500\n") != std::string::npos);
  CHECK(res["schedule_gcode"].get<std::string>().find("M900 K0.06 ; at") != std::string::npos);
  bool z_warning = false;
  for (const auto& w : j["warnings"])
    z_warning |= w.get<std::string>().find("Z shaper is not exported: a Z shaper is exported for Klipper only") !=
                 std::string::npos;
  CHECK(z_warning);

  // Marlin takes one shaper type: the mzv/ei recommendation is refused, exit 2.
  const auto refused = tunekit::test::run_cli({"export", "-f", "marlin", "-c", cfg, fixture("shaper.json")});
  CHECK(refused.code == 2);
  CHECK_THAT(refused.err, Catch::Contains("ZV only"));
}
