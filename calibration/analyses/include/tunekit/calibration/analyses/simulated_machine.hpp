#pragma once
// The machine of a command's runs, as its options name it: "sim", tunekit's simulated printer
// (served for each run on a pseudo-terminal, protocols/machine_host.hpp), or a machine profile
// for the printer on a port. The profile is loaded and the simulator's options are read once
// per command, here; the runner (protocols/runner.hpp) gets them ready.

#include <memory>
#include <string>
#include <vector>

#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/machine_host.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::sim {
struct SimConfig;
class SimPrintBed;
}  // namespace tunekit::sim

namespace tunekit::calibration {

/// tunekit's simulated printer with the truth and faults of `config`, served anew for each run:
/// its truth.json is kept in every run directory, and what it received (sim_received.gcode) and
/// counted (sim_stats.json) when the run ends. What it prints is laid down on `bed` (for the
/// simulated camera, sim/sim_camera.hpp) when one is given; several runs may share one bed.
std::shared_ptr<const protocols::MachineHost> simulated_machine(const sim::SimConfig& config,
                                                                std::shared_ptr<sim::SimPrintBed> bed = {});

/// The same for the printer `profile` describes (sim::SimConfig::for_machine: its firmware, steps,
/// limits and sensors), with `sim_options` ("tau_s=0.5", "fault=drop@12") winning over it.
/// InputError for a bad option.
std::shared_ptr<const protocols::MachineHost> simulated_machine(const machine::MachineProfile& profile,
                                                                const std::vector<std::string>& sim_options);

/// The machine `run.machine` names, ready for the runner, read once for all the runs made with
/// `run`: with "sim", run.profile is the printer simulated (the file `profile_path` names, as
/// tunekit run --profile, or the built-in simulated printer's) and run.host serves it with
/// `sim_options`; otherwise run.profile is the file `run.machine` names and `sim_options` are only
/// checked. InputError for a bad profile or option, or a `profile_path` beside a real machine.
void load_run_machine(protocols::RunOptions& run, const std::string& profile_path,
                      const std::vector<std::string>& sim_options);

}  // namespace tunekit::calibration
