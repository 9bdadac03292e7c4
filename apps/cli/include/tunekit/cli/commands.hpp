#pragma once
// The tunekit command line's parts. Each subcommand lives in its own <name>_cli.cpp and is
// added to the application by its register_* function; run_cli() (run_cli.hpp) puts them
// together.

#include <ostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "tunekit/calibration/results/context.hpp"
#include "tunekit/cli/run_cli.hpp"

namespace tunekit::cli {

using calibration::CliContext;
using calibration::OutputOptions;

/// The result of a subcommand's callback, read by run_cli after parsing.
void set_exit_code(int code);

void register_step(CLI::App& app, CliContext& ctx);
void register_freq(CLI::App& app, CliContext& ctx);
void register_rheo(CLI::App& app, CliContext& ctx);
void register_nozzle(CLI::App& app, CliContext& ctx);
void register_resonance(CLI::App& app, CliContext& ctx);
void register_shaper(CLI::App& app, CliContext& ctx);
void register_linewidth(CLI::App& app, CliContext& ctx);
void register_run(CLI::App& app, CliContext& ctx);
void register_export(CLI::App& app, CliContext& ctx);
void register_calibrate(CLI::App& app, CliContext& ctx);
void register_report(CLI::App& app, CliContext& ctx);
void register_batch(CLI::App& app, CliContext& ctx);
void register_ports(CLI::App& app, CliContext& ctx);
void register_inspect(CLI::App& app, CliContext& ctx);
void register_history(CLI::App& app, CliContext& ctx);
void register_belts(CLI::App& app, CliContext& ctx);
void register_delta(CLI::App& app, CliContext& ctx);
void register_overshoot(CLI::App& app, CliContext& ctx);
void register_profile(CLI::App& app, CliContext& ctx);
void register_thermal(CLI::App& app, CliContext& ctx);

}  // namespace tunekit::cli
