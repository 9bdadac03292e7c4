#pragma once
// Each analysis command's subcommand with its options bound straight into the library's option
// struct, without what the command does when it runs: register_x() (commands.hpp) adds the
// callback that computes and prints, the Python module (python/) parses keyword arguments with
// the same subcommand and calls the same compute function. One binding, so an option's name,
// parsing and default are the same in both. Each returns the subcommand it added to `app`.

#include <CLI/CLI.hpp>

#include "tunekit/calibration/analyses/belts_command.hpp"
#include "tunekit/calibration/analyses/delta_command.hpp"
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/analyses/linewidth_command.hpp"
#include "tunekit/calibration/analyses/nozzle_command.hpp"
#include "tunekit/calibration/analyses/overshoot_command.hpp"
#include "tunekit/calibration/analyses/resonance_command.hpp"
#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/calibration/analyses/thermal_command.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/calibration/results/context.hpp"

namespace tunekit::cli {

using calibration::OutputOptions;

CLI::App* add_step_command(CLI::App& app, calibration::StepOptions& o, OutputOptions& output);
CLI::App* add_freq_command(CLI::App& app, calibration::FreqOptions& o, OutputOptions& output);
CLI::App* add_rheo_command(CLI::App& app, calibration::RheoOptions& o, OutputOptions& output);
CLI::App* add_nozzle_command(CLI::App& app, calibration::NozzleOptions& o, OutputOptions& output);
CLI::App* add_resonance_command(CLI::App& app, calibration::ResonanceOptions& o, OutputOptions& output);
CLI::App* add_shaper_command(CLI::App& app, calibration::ShaperOptions& o, OutputOptions& output);
CLI::App* add_belts_command(CLI::App& app, calibration::BeltsOptions& o, OutputOptions& output);
CLI::App* add_linewidth_command(CLI::App& app, calibration::LinewidthOptions& o, OutputOptions& output);
CLI::App* add_overshoot_command(CLI::App& app, calibration::OvershootOptions& o, OutputOptions& output);
CLI::App* add_delta_command(CLI::App& app, calibration::DeltaOptions& o, OutputOptions& output);
CLI::App* add_thermal_command(CLI::App& app, calibration::ThermalOptions& o, OutputOptions& output);
CLI::App* add_export_command(CLI::App& app, calibration::ExportOptions& o, OutputOptions& output);

}  // namespace tunekit::cli
