// tunekit-sim: a virtual printer on a pseudo-terminal. It speaks the Marlin-flavoured G-code
// protocol, simulates a liquefier with a load cell and axes with resonant modes seen by an
// accelerometer, streams sensor data (M4100), injects faults on request, and writes its truth
// to a JSON file. See docs/machine.md.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/version.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/sim/simulator.hpp"

namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "tunekit-sim: a simulated 3D printer (Marlin-flavoured G-code on a pseudo-terminal) with a liquefier,\n"
      "a load cell, resonant axes and an accelerometer, for tunekit's experiment protocols.",
      "tunekit-sim"};
  std::string link, truth_path, received_path, profile_path;
  std::vector<std::string> options;
  app.add_option("--link", link, "Also make this symlink to the pseudo-terminal (like Klipper's /tmp/printer)");
  app.add_option("--truth", truth_path, "Write the simulated truth (model parameters) to this JSON file");
  app.add_option("--received", received_path, "On exit, write every line received to this file");
  app.add_option("--profile", profile_path,
                 "Simulate the printer this machine profile describes (tunekit's TOML or the firmware's configuration: "
                 "Klipper printer.cfg, Marlin M503 or Configuration.h, RRF config.g): its firmware's planner rules, "
                 "steps per mm, extruder and acceleration limits; --set options win over it");
  app.add_option("-s,--set", options,
                 "Simulator option KEY=VALUE (repeatable): preset=desktop|peek (a direct-drive desktop printer, or "
                 "the thesis' PEEK liquefier with tau 0.45 s), liquefier=fopdt|physics, K=3.5 (N/(mm/s)), tau_s=0.026 "
                 "(s, at tau_ref_feed_mm_s=2.25), tau_flow_exponent=-0.5, theta_s=0.02 (s), force_noise_N=0.02 (N), "
                 "load_cell_rate_hz=200 (Hz), mode_x=48:0.08[:weight] "
                 "(Hz:damping ratio), accel_rate_hz=3200 (Hz), accel_noise_mm_s2=20 (mm/s^2), jerk_mm_s3=1e8 (mm/s^3), "
                 "seed=1, fault=drop@N|garble@N|late-ok@N:MS|disconnect@N|error@N (N: received line count)");
  app.set_version_flag("--version", std::string("tunekit-sim ") + tunekit::core::kVersion);
  app.footer(
      "The pseudo-terminal's path is printed on stdout; the simulator runs until interrupted or a\n"
      "disconnect fault fires. Machine time advances with executed motion only, faster than real time.\n"
      "Examples:\n"
      "  tunekit-sim --link /tmp/tksim --truth truth.json\n"
      "  tunekit-sim --link /tmp/tksim -s tau_s=0.3 -s mode_x=52:0.06 -s fault=garble@20\n"
      "  tunekit-sim --link /tmp/tksim --profile printer.cfg     # a Klipper printer's limits and planner\n"
      "  tunekit run liquefier-step --machine sim --port /tmp/tksim");
  CLI11_PARSE(app, argc, argv);
  try {
    const auto cfg = profile_path.empty() ? tunekit::sim::SimConfig::from_options(options)
                                          : tunekit::sim::SimConfig::for_machine(
                                                tunekit::machine::load_machine_profile(profile_path), options);
    if (!truth_path.empty()) tunekit::core::write_file_atomic(truth_path, cfg.truth().dump(2) + "\n");
    tunekit::sim::SimPtyServer server(cfg);
    if (!link.empty()) {
      std::error_code ec;
      std::filesystem::remove(link, ec);
      std::filesystem::create_symlink(server.path(), link, ec);
      if (ec) throw tunekit::InputError(fmt::format("cannot create the link: {}", ec.message()), link);
    }
    std::cout << server.path() << std::endl;
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    while (!g_stop && !server.disconnected()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    server.stop();
    server.wait();
    if (!received_path.empty()) {
      std::string all;
      for (const auto& l : server.sim().received()) all += l + "\n";
      tunekit::core::write_file_atomic(received_path, all);
    }
    if (!link.empty()) {
      std::error_code ec;
      std::filesystem::remove(link, ec);
    }
    return server.disconnected() ? 3 : 0;
  } catch (const tunekit::Error& e) {
    std::cerr << e.formatted() << "\n";
    return static_cast<int>(e.code());
  }
}
