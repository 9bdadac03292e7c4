// tunekit run: run an experiment protocol on a printer or on the built-in simulated printer,
// journaling every line and sensor sample into a run directory (protocols/runner.hpp).
#include <atomic>
#include <csignal>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/results_json.hpp"
#include "tunekit/cli/run_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::cli {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

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

RunOutcome compute_run(const RunCommandOptions& a) {
  RunOutcome outcome;
  outcome.options = a;
  protocols::RunOptions o = a.run;
  if (!(a.timeout_s > 0)) throw InputError("--timeout must be positive (s)");
  o.link.timeout = std::chrono::milliseconds(static_cast<long>(std::lround(a.timeout_s * 1000)));
  if (!(o.limits.max_duration_s > 0) || !std::isfinite(o.limits.max_duration_s))
    throw InputError("--max-duration must be a positive number of seconds");
  if (o.limits.max_lines == 0) throw InputError("--max-lines must be at least 1");
  for (const auto& p : a.params) {
    const auto eq = p.find('=');
    if (eq == std::string::npos) throw InputError(fmt::format("-p {}: expected NAME=VALUE", p));
    char* end = nullptr;
    const std::string v = p.substr(eq + 1);
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || end != v.c_str() + v.size()) throw InputError(fmt::format("-p {}: '{}' is not a number", p, v));
    if (!std::isfinite(d)) throw InputError(fmt::format("-p {}: '{}' is not a finite number", p, v));
    o.params[p.substr(0, eq)] = d;
  }
  outcome.options.run.params = o.params;
  if (o.machine != "sim" && o.port.empty() && !o.dry_run)
    throw InputError(
        "--port is needed with a machine profile (a serial device, a PTY such as /tmp/printer, or "
        "unix:/tmp/klippy_uds)");
  if (o.machine != "sim" && o.port.empty()) o.port = "(dry run)";
  g_interrupted = false;
  o.abort_flag = &g_interrupted;
  struct SigGuard {
    void (*old)(int);
    SigGuard() : old(std::signal(SIGINT, on_sigint)) {}
    ~SigGuard() { std::signal(SIGINT, old); }
  } guard;

  outcome.result = protocols::run_experiment(o);
  if (!o.dry_run && outcome.result.files.count("truth"))
    outcome.truth = read_json_file(outcome.result.files.at("truth"));
  return outcome;
}

Envelope to_envelope(const RunOutcome& outcome) {
  const auto& a = outcome.options.run;
  const auto& r = outcome.result;
  Envelope env("run");
  nlohmann::json params = nlohmann::json::object();
  for (const auto& [k, v] : a.params) params[k] = v;
  env.set_options({{"protocol", a.protocol},
                   {"axis", a.axis},
                   {"machine", a.machine},
                   {"port", a.port},
                   {"params", params},
                   {"sim", a.sim_options},
                   {"dry_run", a.dry_run}});
  auto& res = env.results();
  res["experiment"] = r.experiment.to_json();
  if (a.dry_run) {
    res["gcode"] = r.gcode;
    return env;
  }
  res["run_dir"] = r.run_dir;
  res["status"] = r.status;
  res["files"] = r.files;
  res["samples"] = r.summary.value("samples", nlohmann::json::object());
  res["link"] = r.summary.value("link", nlohmann::json::object());
  if (outcome.truth) res["truth"] = *outcome.truth;
  return env;
}

void print_text(const RunOutcome& outcome, std::ostream& os) {
  const auto& a = outcome.options.run;
  const auto& r = outcome.result;
  if (a.dry_run) {
    for (const auto& l : r.gcode) os << l << "\n";
    return;
  }
  os << fmt::format("{} {}: {}\n", a.protocol, r.status, r.run_dir);
  for (const auto& [role, path] : r.files) os << fmt::format("  {:<16} {}\n", role, path);
  if (r.files.count("load_cell") && (a.protocol == "liquefier-step" || a.protocol == "liquefier-flow-sweep"))
    os << fmt::format("analyze: tunekit step {} --time time --input feed --output force\n", r.files.at("load_cell"));
  if (r.files.count("accel"))
    os << fmt::format("analyze: tunekit resonance {} --axis {}\n", r.files.at("accel"), a.axis);
}

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
  sub->add_option("-m,--machine", r.machine,
                  fmt::format("'{}' (the built-in simulated printer, default) or a machine profile TOML (limits in mm, "
                              "mm/s, mm/s^2, degC)",
                              r.machine));
  sub->add_option("--port", r.port,
                  "Serial device (/dev/ttyACM0), pseudo-terminal (/tmp/printer) or unix:SOCKET (Klipper API server); "
                  "with --machine sim: an external tunekit-sim link");
  sub->add_option("--baud", r.baud, "Serial baud rate (bit/s)");
  sub->add_option("-p,--param", o.params, "Protocol parameter NAME=VALUE, in the unit its name carries (repeatable)");
  sub->add_option("--sim", r.sim_options,
                  "Simulator option KEY=VALUE (repeatable), e.g. tau_s=0.5 (s), K=3.5 (N/(mm/s)), theta_s=0.04 (s), "
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
  sub->add_flag("--dry-run", r.dry_run,
                "Print the protocol's G-code (checked against the profile) instead of sending it");
  add_output_options(sub, cmd->output);
  sub->footer(protocols_help() +
              "\nExamples:\n"
              "  tunekit run liquefier-step --machine sim\n"
              "  tunekit run axis-sweep --axis x --machine sim -p freq_start_hz=20 -p freq_end_hz=80\n"
              "  tunekit run liquefier-step --dry-run -p feed_high_mm_s=4\n"
              "  tunekit run axis-sweep --axis y --machine printer.toml --port unix:/tmp/klippy_uds\n"
              "  tunekit run liquefier-step --machine sim --sim fault=garble@12 --json\n"
              "Each run directory holds journal.jsonl, the sensor CSVs, protocol.gcode, run.json and, on the\n"
              "simulator, truth.json. Exit code 3: the machine or link failed (the partial run is kept).");
  sub->callback([cmd, &ctx] {
    cmd->options.run.progress = [&ctx](const std::string& m) {
      if (ctx.verbosity > 0) ctx.err << "tunekit: " << m << "\n";
    };
    set_exit_code(report_outcome(compute_run(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
