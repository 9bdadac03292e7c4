// tunekit run: run an experiment protocol on a printer or on the built-in simulated printer,
// journaling every line and sensor sample into a run directory (protocols/runner.hpp).
#include <atomic>
#include <csignal>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::cli {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

struct RunArgs {
  std::string protocol;
  std::string axis = "x";
  std::string machine = "sim";
  std::string port;
  int baud = 250000;
  std::vector<std::string> params;
  std::vector<std::string> sim;
  std::string run_dir;
  std::string runs_root = "runs";
  double timeout_s = 10;
  int retries = 3;
  bool dry_run = false;
  double max_duration_s = protocols::ProtocolLimits{}.max_duration_s;
  std::size_t max_lines = protocols::ProtocolLimits{}.max_lines;
  OutputOptions output;
};

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

int run_run(const RunArgs& a, CliContext& ctx) {
  protocols::RunOptions o;
  o.protocol = a.protocol;
  o.axis = a.axis;
  o.machine = a.machine;
  o.port = a.port;
  o.baud = a.baud;
  o.run_dir = a.run_dir;
  o.runs_root = a.runs_root;
  o.sim_options = a.sim;
  o.dry_run = a.dry_run;
  if (!(a.timeout_s > 0)) throw InputError("--timeout must be positive (s)");
  o.link.timeout = std::chrono::milliseconds(static_cast<long>(std::lround(a.timeout_s * 1000)));
  o.link.max_retries = a.retries;
  if (!(a.max_duration_s > 0) || !std::isfinite(a.max_duration_s)) throw InputError("--max-duration must be a positive number of seconds");
  if (a.max_lines == 0) throw InputError("--max-lines must be at least 1");
  o.limits.max_duration_s = a.max_duration_s;
  o.limits.max_lines = a.max_lines;
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
  if (a.machine != "sim" && a.port.empty() && !a.dry_run)
    throw InputError("--port is needed with a machine profile (a serial device, a PTY such as /tmp/printer, or unix:/tmp/klippy_uds)");
  if (a.machine != "sim" && a.port.empty()) o.port = "(dry run)";
  o.progress = [&ctx](const std::string& m) {
    if (ctx.verbosity > 0) ctx.err << "tunekit: " << m << "\n";
  };
  g_interrupted = false;
  o.abort_flag = &g_interrupted;
  struct SigGuard {
    void (*old)(int);
    SigGuard() : old(std::signal(SIGINT, on_sigint)) {}
    ~SigGuard() { std::signal(SIGINT, old); }
  } guard;

  const auto r = protocols::run_experiment(o);

  Envelope env("run");
  nlohmann::json params = nlohmann::json::object();
  for (const auto& [k, v] : o.params) params[k] = v;
  env.set_options({{"protocol", a.protocol}, {"axis", a.axis}, {"machine", a.machine}, {"port", a.port},
                   {"params", params}, {"sim", a.sim}, {"dry_run", a.dry_run}});
  auto& res = env.results();
  res["experiment"] = r.experiment.to_json();
  if (a.dry_run) {
    res["gcode"] = r.gcode;
    if (!a.output.json)
      for (const auto& l : r.gcode) ctx.out << l << "\n";
    return emit(env, a.output, ctx);
  }
  res["run_dir"] = r.run_dir;
  res["status"] = r.status;
  res["files"] = r.files;
  res["samples"] = r.summary.value("samples", nlohmann::json::object());
  res["link"] = r.summary.value("link", nlohmann::json::object());
  if (r.files.count("truth")) {
    std::ifstream f(r.files.at("truth"));
    std::stringstream ss;
    ss << f.rdbuf();
    res["truth"] = nlohmann::json::parse(ss.str());
  }
  if (!a.output.json) {
    ctx.out << fmt::format("{} {}: {}\n", a.protocol, r.status, r.run_dir);
    for (const auto& [role, path] : r.files) ctx.out << fmt::format("  {:<16} {}\n", role, path);
    if (r.files.count("load_cell") && a.protocol == "liquefier-step")
      ctx.out << fmt::format("analyze: tunekit step {} --time time --input feed --output force\n", r.files.at("load_cell"));
    if (r.files.count("load_cell") && a.protocol == "liquefier-flow-sweep")
      ctx.out << fmt::format("analyze: tunekit step {} --time time --input feed --output force --min-step 0.02 "
                             "--operating-points arrival\n",
                             r.files.at("load_cell"));
    if (r.files.count("accel"))
      ctx.out << fmt::format("analyze: tunekit resonance {} --axis {}\n", r.files.at("accel"), a.axis);
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_run(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<RunArgs>();
  auto* sub = app.add_subcommand("run", "Run an experiment protocol on a printer or the simulator");
  std::vector<std::string> names;
  for (const auto& s : protocols::protocol_specs()) names.push_back(s.name);
  sub->add_option("protocol", args->protocol, "Experiment protocol (listed below)")->required()->check(CLI::IsMember(names));
  sub->add_option("--axis", args->axis, "Axis of an axis protocol: x or y")->check(CLI::IsMember({"x", "y"}));
  sub->add_option("-m,--machine", args->machine,
                  "'sim' (the built-in simulated printer, default) or a machine profile TOML (limits in mm, mm/s, mm/s^2, degC)");
  sub->add_option("--port", args->port,
                  "Serial device (/dev/ttyACM0), pseudo-terminal (/tmp/printer) or unix:SOCKET (Klipper API server); "
                  "with --machine sim: an external tunekit-sim link");
  sub->add_option("--baud", args->baud, "Serial baud rate (bit/s)");
  sub->add_option("-p,--param", args->params, "Protocol parameter NAME=VALUE, in the unit its name carries (repeatable)");
  sub->add_option("--sim", args->sim,
                  "Simulator option KEY=VALUE (repeatable), e.g. tau_s=0.5 (s), K=3.5 (N/(mm/s)), theta_s=0.04 (s), "
                  "mode_x=48:0.08 (Hz:damping ratio), liquefier=physics, fault=garble@12; see docs/machine.md");
  sub->add_option("--run-dir", args->run_dir, "Run directory (default: RUNS_ROOT/PROTOCOL-UTCSTAMP)");
  sub->add_option("--runs-root", args->runs_root, "Where run directories are created (default: runs)");
  sub->add_option("--timeout", args->timeout_s, "Silence allowed while waiting for the firmware's ok (s)");
  sub->add_option("--retries", args->retries, "Re-sends of a line nobody answered before giving up (count)");
  sub->add_option("--max-duration", args->max_duration_s,
                  "Refuse a protocol that takes longer than this much machine time (s; default 7200)");
  sub->add_option("--max-lines", args->max_lines, "Refuse a protocol of more G-code lines than this (default 1000000)");
  sub->add_flag("--dry-run", args->dry_run, "Print the protocol's G-code (checked against the profile) instead of sending it");
  add_output_options(sub, args->output);
  sub->footer(protocols_help() +
              "\nExamples:\n"
              "  tunekit run liquefier-step --machine sim\n"
              "  tunekit run axis-sweep --axis x --machine sim -p freq_start_hz=20 -p freq_end_hz=80\n"
              "  tunekit run liquefier-step --dry-run -p feed_high_mm_s=4\n"
              "  tunekit run axis-sweep --axis y --machine printer.toml --port unix:/tmp/klippy_uds\n"
              "  tunekit run liquefier-step --machine sim --sim fault=garble@12 --json\n"
              "Each run directory holds journal.jsonl, the sensor CSVs, protocol.gcode, run.json and, on the\n"
              "simulator, truth.json. Exit code 3: the machine or link failed (the partial run is kept).");
  sub->callback([args, &ctx] { set_exit_code(run_run(*args, ctx)); });
}

}  // namespace tunekit::cli
