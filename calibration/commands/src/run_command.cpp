// tunekit run: run an experiment protocol on a printer or on the built-in simulated printer,
// journaling every line and sensor sample into a run directory (protocols/runner.hpp).
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/commands/run_command.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/protocols/experiments.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::calibration {
namespace {

// Accepted ranges of run's numeric options (a value beyond is a typing error, and some would
// wrap: -1 lines is 2^64-1 as an unsigned count, an infinite timeout overflows the milliseconds).
// --timeout, s: a day of silence is a dead link; far inside the range of the milliseconds count.
constexpr double kMaxTimeout_s = 86400;
// --timeout, s: the link counts milliseconds; less than one would round to no wait at all.
constexpr double kMinTimeout_s = 0.001;
// --retries: each waits up to --timeout; a hundred turn a dead link into hours of waiting.
constexpr int kMaxRetries = 100;
// --baud, bit/s: the highest rate termios names, B4000000 (Linux, include/uapi/asm-generic/termbits.h).
constexpr int kMaxBaud = 4'000'000;
// --max-duration, s: one week of machine time; no calibration protocol runs longer.
constexpr double kMaxDuration_s = 7 * 86400.0;

/// Refuses an out-of-range numeric option of run (InputError, exit 2), naming the accepted range.
void check_run_ranges(const RunCommandOptions& a) {
  const auto& r = a.run;
  if (!(a.timeout_s >= kMinTimeout_s && a.timeout_s <= kMaxTimeout_s))
    throw InputError(fmt::format("--timeout {} s is out of range (accepted: {} to {} s)", a.timeout_s, kMinTimeout_s,
                                 kMaxTimeout_s));
  if (r.link.max_retries < 0 || r.link.max_retries > kMaxRetries)
    throw InputError(fmt::format("--retries {} is out of range (accepted: 0 to {})", r.link.max_retries, kMaxRetries));
  if (r.baud <= 0 || r.baud > kMaxBaud)
    throw InputError(fmt::format("--baud {} is out of range (accepted: 1 to {} bit/s)", r.baud, kMaxBaud));
  if (!(r.limits.max_duration_s > 0 && r.limits.max_duration_s <= kMaxDuration_s))
    throw InputError(fmt::format("--max-duration {} s is out of range (accepted: above 0 to {} s)",
                                 r.limits.max_duration_s, kMaxDuration_s));
  // Every line takes at least one byte of the protocol's byte cap: more lines cannot fit.
  if (r.limits.max_lines == 0 || r.limits.max_lines > r.limits.max_bytes)
    throw InputError(fmt::format("--max-lines {} is out of range (accepted: 1 to {}, the G-code byte cap)",
                                 r.limits.max_lines, r.limits.max_bytes));
}

/// Bed slinger: the mass the sweep wants on the bed (-p load_kg). The simulated printer carries
/// it (unless --sim bed_load_kg says otherwise); a technician is asked to place it on a terminal,
/// and without one the option stands for the mass placed (the run records it with the sweep).
void place_bed_load(const RunCommandOptions& a, const protocols::RunOptions& o, std::vector<std::string>& sim) {
  const auto it = o.params.find("load_kg");
  if (it == o.params.end() || !(it->second > 0) || o.dry_run) return;
  if (o.machine == "sim") {
    const bool given =
        std::any_of(sim.begin(), sim.end(), [](const auto& s) { return s.rfind("bed_load_kg=", 0) == 0; });
    if (!given) sim.push_back(fmt::format("bed_load_kg={}", it->second));
    return;
  }
  auto at = [&](const char* key, const char* axis) {
    const auto p = o.params.find(key);
    return p == o.params.end() ? fmt::format("{} at the middle of its travel", axis)
                               : fmt::format("{} {} mm", axis, p->second);
  };
  const std::string instruction = fmt::format("place {} kg on the bed ({}, {}), fixed so it cannot slide", it->second,
                                              at("load_x_mm", "x"), at("load_y_mm", "y"));
  if (a.confirm_setup && !a.confirm_setup(instruction))
    throw InputError("the mass on the bed was not confirmed: nothing was sent");
}

}  // namespace

RunOutcome compute_run(const RunCommandOptions& a) {
  RunOutcome outcome;
  outcome.options = a;
  protocols::RunOptions o = a.run;
  check_run_ranges(a);
  o.link.timeout = std::chrono::milliseconds(static_cast<long>(std::lround(a.timeout_s * 1000)));
  for (const auto& p : a.params) {
    const auto eq = p.find('=');
    if (eq == std::string::npos) throw InputError(fmt::format("-p {}: expected NAME=VALUE", p));
    const std::string v = p.substr(eq + 1);
    const auto parsed = core::parse_decimal(v);
    if (!parsed) throw InputError(fmt::format("-p {}: '{}' is not a decimal number (such as 12, 0.5 or 1e-3)", p, v));
    const double d = *parsed;
    if (!std::isfinite(d)) throw InputError(fmt::format("-p {}: '{}' is not a finite number", p, v));
    o.params[p.substr(0, eq)] = d;
  }
  outcome.options.run.params = o.params;
  if (o.machine != "sim" && o.port.empty() && !o.dry_run)
    throw InputError(
        "--port is needed with a machine profile (a serial device, a PTY such as /tmp/printer, or "
        "unix:/tmp/klippy_uds)");
  if (o.machine != "sim" && o.port.empty()) o.port = "(dry run)";
  std::vector<std::string> sim_options = a.sim_options;
  place_bed_load(a, o, sim_options);
  outcome.options.sim_options = sim_options;
  load_run_machine(o, a.profile_path, sim_options);
  outcome.result = protocols::run_experiment(o);
  if (!o.dry_run && outcome.result.files.count(protocols::RunFile::truth))
    outcome.truth = read_json_file(outcome.result.files.at(protocols::RunFile::truth));
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
                   {"sim", outcome.options.sim_options},
                   {"dry_run", a.dry_run}});
  auto& res = env.results();
  res["experiment"] = r.experiment.to_json();
  if (a.dry_run) {
    res["gcode"] = r.gcode;
    return env;
  }
  res["run_dir"] = r.run_dir;
  res["status"] = r.status;
  res["files"] = protocols::to_json(r.files);
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
  for (const auto& [role, path] : r.files) os << fmt::format("  {:<16} {}\n", protocols::to_string(role), path);
  const auto id = protocols::protocol_spec(a.protocol).id;
  if (r.files.count(protocols::RunFile::load_cell) &&
      (id == protocols::Protocol::liquefier_step || id == protocols::Protocol::liquefier_flow_sweep))
    os << fmt::format("analyze: tunekit step {} --time time --input feed --output force\n",
                      r.files.at(protocols::RunFile::load_cell));
  if (r.files.count(protocols::RunFile::accel))
    os << fmt::format("analyze: tunekit resonance {} --axis {}\n", r.files.at(protocols::RunFile::accel), a.axis);
}

}  // namespace tunekit::calibration
