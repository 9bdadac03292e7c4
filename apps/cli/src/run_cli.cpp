// tunekit run: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/commands/run_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/stop_signals.hpp"
#include <unistd.h>

#include <atomic>
#include <iostream>
#include <cmath>
#include <csignal>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

std::string protocols_help() {
  std::string s = "Protocols (set parameters with -p NAME=VALUE; units are in the names):\n";
  for (const auto& spec : protocols::protocol_specs()) {
    s += fmt::format("  {}{}: {}\n", spec.name, spec.uses_axis ? " (--axis x|y)" : "", spec.description);
    for (const auto& p : spec.params) {
      const std::string def = std::isnan(p.default_value) ? "machine" : fmt::format("{:g}", p.default_value);
      s += fmt::format("      {:<20} [{}] default {}: {}\n", p.name, p.unit.empty() ? "-" : p.unit, def, p.help);
    }
    if (!spec.sensors.empty()) {
      s += "      records:";
      for (const auto& x : spec.sensors) s += " " + x;
      s += "\n";
    }
  }
  return s;
}

}  // namespace

namespace {
struct RunCommand {
  RunCommandOptions options;
  OutputOptions output;
};
}  // namespace

void register_run(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<RunCommand>();
  RunCommandOptions& o = cmd->options;
  protocols::RunOptions& r = o.run;
  auto* sub = app.add_subcommand("run", "Run an experiment protocol on a printer or the simulator");
  std::vector<std::string> names;
  for (const auto& s : protocols::protocol_specs()) names.push_back(s.name);
  sub->add_option("protocol", r.protocol, "Experiment protocol (listed below)")
      ->required()
      ->check(CLI::IsMember(names));
  sub->add_option("--axis", r.axis, "Axis of an axis protocol: x or y")->check(CLI::IsMember({"x", "y"}));
  sub->add_option(
      "-m,--machine", r.machine,
      fmt::format("'{}' (the built-in simulated printer, default) or a machine profile: TOML (limits in mm, "
                  "mm/s, mm/s^2, degC) or the firmware's configuration (Klipper printer.cfg, Marlin "
                  "Configuration.h, RepRapFirmware config.g; see tunekit profile)",
                  r.machine));
  sub->add_option("--profile", o.profile_path,
                  "With --machine sim: the printer to simulate, a machine profile TOML or its firmware configuration "
                  "(its limits, firmware, steps and extruder)");
  sub->add_option("--port", r.port,
                  "Serial device (/dev/ttyACM0), pseudo-terminal (/tmp/printer) or unix:SOCKET (Klipper API server); "
                  "with --machine sim: an external tunekit-sim link");
  sub->add_option("--baud", r.baud, "Serial baud rate (bit/s)");
  sub->add_option("-p,--param", o.params, "Protocol parameter NAME=VALUE, in the unit its name carries (repeatable)");
  sub->add_option(
      "--sim", o.sim_options,
      "Simulator option KEY=VALUE (repeatable), e.g. preset=peek (the thesis' PEEK liquefier), tau_s=0.5 (s), "
      "K=3.5 (N/(mm/s)), theta_s=0.04 (s), "
      "mode_x=48:0.08 (Hz:damping ratio), liquefier=physics, fault=garble@12; see docs/machine.md");
  sub->add_option("--run-dir", r.run_dir, "Run directory (default: RUNS_ROOT/PROTOCOL-UTCSTAMP)");
  sub->add_option("--runs-root", r.runs_root,
                  fmt::format("Where run directories are created (default: {})", r.runs_root));
  sub->add_option("--timeout", o.timeout_s, "Silence allowed while waiting for the firmware's ok (s)");
  sub->add_option("--retries", r.link.max_retries, "Re-sends of a line nobody answered before giving up (count)");
  sub->add_option("--max-duration", r.limits.max_duration_s,
                  fmt::format("Refuse a protocol that takes longer than this much machine time (s; default {:g})",
                              r.limits.max_duration_s));
  sub->add_option("--max-lines", r.limits.max_lines,
                  fmt::format("Refuse a protocol of more G-code lines than this (default {})", r.limits.max_lines));
  sub->add_flag("--keep-heaters", r.keep_heaters,
                "Leave the hot end and bed at the protocol's temperatures when it ends (default: a protocol that "
                "heated turns them off)");
  sub->add_flag("--dry-run", r.dry_run,
                "Print the protocol's G-code (checked against the profile) instead of sending it");
  add_output_options(sub, cmd->output);
  sub->footer(protocols_help() +
              "\nExamples:\n"
              "  tunekit run liquefier-step --machine sim\n"
              "  tunekit run axis-sweep --axis x --machine sim -p freq_start_hz=20 -p freq_end_hz=80\n"
              "  tunekit run liquefier-step --dry-run -p feed_high_mm_s=4\n"
              "  tunekit run axis-sweep --axis x --machine sim --profile printer.cfg --dry-run\n"
              "  tunekit run axis-sweep --axis y --machine printer.toml --port unix:/tmp/klippy_uds\n"
              "  tunekit run liquefier-step --machine sim --sim fault=garble@12 --json\n"
              "Each run directory holds journal.jsonl, the sensor CSVs, protocol.gcode, run.json and, on the\n"
              "simulator, truth.json. Exit code 3: the machine or link failed (the partial run is kept); 130, 143,\n"
              "129: stopped by SIGINT, SIGTERM, SIGHUP (motion stopped, heaters off; run.json says where).\n"
              "RepRapFirmware's web server password (M551): the environment variable TUNEKIT_RRF_PASSWORD, or\n"
              "[network] password in the profile; it is never printed.");
  sub->callback([cmd, &ctx] {
    cmd->options.run.progress = [&ctx](const std::string& m) {
      if (ctx.verbosity > 0) ctx.err << "tunekit: " << m << "\n";
    };
    // A set-up step the technician does (a mass on the bed) is asked for on a terminal only.
    if (::isatty(STDIN_FILENO) != 0 && ctx.interactive)
      cmd->options.confirm_setup = [&ctx](const std::string& instruction) {
        ctx.err << "tunekit: " << instruction << "; then press Enter (or type 'no' to stop): ";
        ctx.err.flush();
        std::string answer;
        return static_cast<bool>(std::getline(std::cin, answer)) && answer != "no" && answer != "n";
      };
    // A stop signal at any instant, reading and printing the results included, ends the command
    // with exit code 128 + its number and run.json saying where (stop_signals.hpp).
    const protocols::StopSignals stop_signals;
    const RunOutcome outcome = compute_run(cmd->options);
    protocols::throw_if_stopped_after_run(outcome.result, "after the run had ended, while reading its results");
    const int code = report_outcome(outcome, cmd->output, ctx);
    protocols::throw_if_stopped_after_run(outcome.result, "after the run had ended, while printing its results");
    set_exit_code(code);
  });
}

}  // namespace tunekit::cli
