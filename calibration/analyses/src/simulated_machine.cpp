// The simulated printer as the runner's machine (simulated_machine.hpp).
#include "tunekit/calibration/analyses/simulated_machine.hpp"

#include <array>
#include <functional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/sim/builtin_profile.hpp"
#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/sim/simulator.hpp"

namespace tunekit::calibration {
namespace {

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

/// The simulated Marlin build's answer to what identify() asks about FT_MOTION (M493, and M493 V
/// after a 2025-form report), for planning (a dry run) on the simulator.
firmware::FtMotionReport sim_m493_report(const sim::SimConfig& cfg) {
  if (cfg.ft_motion == "none") return {};
  sim::Simulator s(cfg);
  auto ask = [&s](const char* cmd) {
    std::string out;
    s.handle_line(cmd, [&out](std::string_view t) { out += t; });
    std::vector<std::string> lines;
    for (std::size_t b = 0, e; (e = out.find('\n', b)) != std::string::npos; b = e + 1)
      lines.push_back(out.substr(b, e - b));
    return lines;
  };
  auto answer = ask("M493");
  if (firmware::parse_m493_report(answer).form == firmware::M493Form::axis_list) {
    const auto v = ask("M493 V");
    answer.insert(answer.end(), v.begin(), v.end());
  }
  return firmware::parse_m493_report(answer);
}

/// One run's simulator on a pseudo-terminal.
class ServedSimulator final : public protocols::ServedMachine {
 public:
  ServedSimulator(const sim::SimConfig& config, const std::shared_ptr<sim::SimPrintBed>& bed)
      : server_(config, deposit_on(bed)) {}
  std::string port() const override { return server_.path(); }
  std::string http_url() const override { return server_.http_url(); }

  /// Stops the simulator and keeps what it received and counted beside the run's data.
  void stop(machine::Journal& journal, protocols::RunFiles& files) override {
    server_.stop();
    server_.wait();
    const auto received = server_.sim().received();
    core::write_file_atomic(journal.path("sim_received.gcode"), join_lines(received));
    core::write_file_atomic(journal.path("sim_stats.json"),
                            nlohmann::json{{"lines_received", received.size()},
                                           {"accel_samples_sent", server_.sim().accel_samples_sent()},
                                           {"load_cell_samples_sent", server_.sim().load_cell_samples_sent()},
                                           {"disconnected", server_.disconnected()},
                                           {"halted", server_.sim().halted()},
                                           {"hot_end",
                                            {{"target_c", server_.sim().hot_end().target_c()},
                                             {"heater_duty", server_.sim().hot_end().duty()},
                                             {"fan_duty", server_.sim().hot_end().fan_duty()}}},
                                           {"machine_time_s", server_.sim().time_s()}}
                                    .dump(2) +
                                "\n");
    files[protocols::RunFile::sim_received] = journal.path("sim_received.gcode");
  }

 private:
  /// What the simulator prints, laid down on `bed` (nothing without one).
  static std::function<void(sim::Simulator&)> deposit_on(const std::shared_ptr<sim::SimPrintBed>& bed) {
    if (!bed) return {};
    return [bed](sim::Simulator& s) {
      s.deposit_sink = [bed](double t, const std::array<double, 4>& pos, double v, double q) {
        bed->deposit(t, pos, v, q);
      };
    };
  }

  sim::SimPtyServer server_;
};

class SimulatorHost final : public protocols::MachineHost {
 public:
  SimulatorHost(const sim::SimConfig& config, std::shared_ptr<sim::SimPrintBed> bed)
      : config_(config), bed_(std::move(bed)), dialect_(planned(config)), truth_(config.truth().dump(2) + "\n") {}

  firmware::Dialect planned_dialect() const override { return dialect_; }

  std::unique_ptr<protocols::ServedMachine> start(machine::Journal& journal, protocols::RunFiles& files,
                                                  const std::string& port) const override {
    core::write_file_atomic(journal.path("truth.json"), truth_);
    files[protocols::RunFile::truth] = journal.path("truth.json");
    if (!port.empty()) return nullptr;
    return std::make_unique<ServedSimulator>(config_, bed_);
  }

 private:
  /// The simulated printer's firmware (its "firmware=" option, Marlin by default) with, for
  /// Marlin, the M493 report its build gives (what identify() reads).
  static firmware::Dialect planned(const sim::SimConfig& cfg) {
    firmware::Dialect dialect(cfg.firmware.empty() ? firmware::Firmware::marlin
                                                   : firmware::firmware_from_name(cfg.firmware));
    if (dialect.firmware() == firmware::Firmware::marlin) dialect.set_ft_motion(sim_m493_report(cfg));
    return dialect;
  }

  sim::SimConfig config_;
  std::shared_ptr<sim::SimPrintBed> bed_;
  firmware::Dialect dialect_;
  std::string truth_;  ///< truth.json's text
};

}  // namespace

std::shared_ptr<const protocols::MachineHost> simulated_machine(const sim::SimConfig& config,
                                                                std::shared_ptr<sim::SimPrintBed> bed) {
  return std::make_shared<SimulatorHost>(config, std::move(bed));
}

std::shared_ptr<const protocols::MachineHost> simulated_machine(const machine::MachineProfile& profile,
                                                                const std::vector<std::string>& sim_options) {
  return simulated_machine(sim::SimConfig::for_machine(profile, sim_options));
}

void load_run_machine(protocols::RunOptions& run, const std::string& profile_path,
                      const std::vector<std::string>& sim_options) {
  if (run.machine == "sim") {
    run.profile = profile_path.empty() ? sim::builtin_sim_profile() : machine::load_machine_profile(profile_path);
    run.host = simulated_machine(run.profile, sim_options);
    return;
  }
  if (!profile_path.empty() && profile_path != run.machine)
    throw InputError(
        "a real machine's profile is --machine FILE; --profile describes the printer --machine sim simulates");
  run.profile = machine::load_machine_profile(run.machine);
  // Bad simulator options fail as on the simulator, though a printer does not use them.
  (void)sim::SimConfig::from_options(sim_options);
  run.host = nullptr;
}

}  // namespace tunekit::calibration
