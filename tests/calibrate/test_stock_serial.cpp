// Stock printers over a serial link: the simulated printer serves a pseudo-terminal with the
// limits and planner of a stock Klipper configuration (a RAMPS board's example printer, the
// Prusa MINI+ whose extrude-only acceleration Klipper computes as 332.6 mm/s^2, and a Kossel
// delta), and `tunekit calibrate --machine PTY --profile P` runs it with default settings as a
// technician would: it exits 0, the step and frequency-response taus agree, the advance's 95 %
// interval holds the simulated liquefier's V(Q)/Q, the axes' intervals hold the simulated modes,
// and no proposed acceleration exceeds the printer's limit.
#include <catch2/catch.hpp>

#include <cmath>

#include <nlohmann/json.hpp>

#include "test_support.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/machine/profile_import.hpp"
#include "tunekit/sim/simulator.hpp"

namespace {

/// The melt volume the desktop liquefier stores at feed u (mm of filament): the integral of its
/// tau(u) (held below its floor feed), as the simulator's truth describes it.
double stored_mm(const nlohmann::json& liquefier, double u) {
  const double tau = liquefier.at("tau_s"), e = liquefier.at("tau_flow_exponent"),
               ref = liquefier.at("tau_ref_feed_mm_s"), floor = liquefier.at("tau_floor_feed_mm_s");
  return floor * tau * std::pow(floor / ref, e) +
         tau * std::pow(ref, -e) * (std::pow(u, e + 1) - std::pow(floor, e + 1)) / (e + 1);
}

struct SerialRun {
  tunekit::test::CliRun cli;
  nlohmann::json results, truth;
  tunekit::machine::MachineProfile profile;
};

SerialRun calibrate_over_serial(const std::string& config, const std::string& name) {
  tunekit::machine::ProfileImportOptions io;
  io.sensors = {"accelerometer", "load_cell"};
  SerialRun r;
  r.profile = tunekit::machine::import_machine_profile(tunekit::test::dataset("klipper_configs/" + config), io);
  const std::string dir = tunekit::test::scratch_dir(name);
  const std::string toml = dir + "/printer.toml";
  tunekit::core::write_file_atomic(toml, tunekit::machine::machine_profile_toml(r.profile));
  const auto cfg = tunekit::sim::SimConfig::for_machine(r.profile, {"seed=5"});
  r.truth = cfg.truth();
  tunekit::sim::SimPtyServer server(cfg);
  r.cli = tunekit::test::run_cli({"calibrate", "--machine", server.path(), "--profile", toml, "--out", dir + "/run"});
  server.stop();
  server.wait();
  if (r.cli.code == 0) r.results = tunekit::test::read_json(dir + "/run/results.json").at("results");
  return r;
}

void check_serial_run(const SerialRun& r) {
  INFO(r.cli.err);
  REQUIRE(r.cli.code == 0);
  CHECK(r.cli.err.find("do NOT agree") == std::string::npos);
  for (const auto& a : r.results.at("agreement")) CHECK(a.at("agree").get<bool>());
  // The advance at its design feed holds the simulated liquefier's stored melt over that feed.
  const auto& comp = r.results.at("compensators");
  const double feed = comp.at("design").at("design_feed_mm_s").get<double>();
  const double k_true = stored_mm(r.truth.at("liquefier"), feed) / feed;
  INFO("advance " << comp.at("settings").at("pa_k_s") << " " << comp.at("pa_k_ci95") << ", plant " << k_true);
  CHECK(comp.at("pa_k_ci95")[0].get<double>() <= k_true);
  CHECK(k_true <= comp.at("pa_k_ci95")[1].get<double>());
  for (const char* axis : {"x", "y"}) {
    const auto& a = r.results.at("axes").at(axis);
    const auto& truth = r.truth.at("axes").at(axis).at("modes").at(0);
    INFO("axis " << axis << ": " << a.at("modes").at(0).dump() << " truth " << truth.dump());
    const auto& ci = a.at("modes").at(0).at("freq_ci95");
    CHECK(ci[0].get<double>() <= truth.at("freq_hz").get<double>());
    CHECK(truth.at("freq_hz").get<double>() <= ci[1].get<double>());
    // Never more than the printer's own limit.
    CHECK(a.at("proposed_max_accel_mm_s2").get<double>() <= r.profile.axis(axis).max_accel_mm_s2);
  }
}

}  // namespace

TEST_CASE("calibrate over a serial link to a RAMPS printer's stock limits: defaults hold, taus agree, intervals hold",
          "[repeats]") {
  check_serial_run(calibrate_over_serial("generic-ramps.cfg", "serial_ramps"));
}

TEST_CASE("calibrate over a serial link to a Prusa MINI+'s stock limits (extruder 332.6 mm/s^2)", "[repeats]") {
  const auto r = calibrate_over_serial("printer-prusa-mini-plus-2020.cfg", "serial_prusa_mini");
  CHECK(r.profile.extruder.max_accel_mm_s2 == Approx(332.6).epsilon(1e-3));
  check_serial_run(r);
}

TEST_CASE("calibrate over a serial link to a Kossel delta's stock limits", "[repeats]") {
  const auto r = calibrate_over_serial("printer-anycubic-kossel-plus-2017.cfg", "serial_kossel");
  CHECK(r.profile.kinematics == "delta");
  check_serial_run(r);
}

TEST_CASE("run --machine sim --profile P simulates P: run.json names it and the G-code keeps its limits") {
  const std::string cfg = tunekit::test::dataset("klipper_configs/printer-prusa-mini-plus-2020.cfg");
  const std::string dir = tunekit::test::scratch_dir("run_sim_profile") + "/run";
  const auto r = tunekit::test::run_cli({"run", "liquefier-flow-sweep", "--machine", "sim", "--profile", cfg,
                                         "--run-dir", dir, "--sim", "force_noise_N=0"});
  INFO(r.err);
  // The stock file lists no load cell: the gate refuses the protocol before anything is sent.
  CHECK(r.code == 2);
  CHECK(r.err.find("load_cell") != std::string::npos);
  // With the load cell declared, it runs with the MINI+'s limits.
  tunekit::machine::ProfileImportOptions io;
  io.sensors = {"load_cell"};
  const auto profile = tunekit::machine::import_machine_profile(cfg, io);
  const std::string toml = tunekit::test::scratch_dir("run_sim_profile_toml") + "/mini.toml";
  tunekit::core::write_file_atomic(toml, tunekit::machine::machine_profile_toml(profile));
  const auto ok = tunekit::test::run_cli(
      {"run", "liquefier-flow-sweep", "--machine", "sim", "--profile", toml, "--run-dir", dir, "--json"});
  INFO(ok.err);
  REQUIRE(ok.code == 0);
  const auto run = tunekit::test::read_json(dir + "/run.json");
  CHECK(run.at("profile") == profile.name);
  CHECK(run.at("profile_source") == toml);
  const auto& params = run.at("experiment").at("params");
  CHECK(params.at("accel_mm_s2").get<double>() <= profile.extruder.max_accel_mm_s2);
  // The simulated printer is the MINI+: Klipper's planner with its extrude-only acceleration.
  const auto truth = tunekit::test::read_json(dir + "/truth.json");
  CHECK(truth.at("firmware") == "klipper");
  CHECK(truth.at("planner").at("max_extrude_only_accel_mm_s2").get<double>() ==
        Approx(profile.extruder.max_accel_mm_s2));
  // Every acceleration the protocol sets is a whole number at or below the extruder's limit.
  const std::string gcode = tunekit::test::read_text(dir + "/protocol.gcode");
  CHECK(gcode.find("SET_VELOCITY_LIMIT ACCEL=332\n") != std::string::npos);
  CHECK(gcode.find("ACCEL=333") == std::string::npos);
}
