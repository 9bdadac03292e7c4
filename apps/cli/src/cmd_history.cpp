// tunekit history: what changed on a machine, and since when. Results recorded with
// `--record --machine-id NAME` (or imported from archived run directories and batch
// summaries) are kept per machine in a SQLite file (default) or a farm's PostgreSQL server:
//   tunekit history list    [--machine M]            machines, or one machine's records
//   tunekit history show    ID                       one record: inputs, quantities, result
//   tunekit history trend   [--machine M] [-q NAME]  each quantity against the machine's baseline
//   tunekit history report  --out fleet.html         one row per machine, sparklines, drift flagged
//   tunekit history import  PATH...                  run directories, results and batch summaries
//                                                    (cmd_history_import.cpp)
// Drift is a change from the baseline larger than the combined uncertainty of the two runs
// (tunekit/history/drift.hpp); `--require 'drift.x.freq_hz>-5%'` gates CI on it.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/history_command.hpp"
#include "tunekit/cli/history_record.hpp"
#include "tunekit/cli/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/store.hpp"

#include "history_common.hpp"

namespace tunekit::cli {

using history_cmd::hist_db_of;
using history_cmd::hist_machines;
using history_cmd::hist_number;

HistoryListOutcome compute_history_list(const HistoryOptions& a) {
  HistoryListOutcome out;
  out.options = a;
  history::Store store(hist_db_of(a));
  out.db = store.connection().name();
  if (a.machines.empty()) out.machines = store.machines();
  else
    for (const auto& machine : hist_machines(store, a.machines))
      out.records.emplace_back(machine, store.records(machine));
  return out;
}

Envelope to_envelope(const HistoryListOutcome& o) {
  Envelope env("history list");
  env.set_options({{"db", o.db}, {"machines", o.options.machines}});
  if (o.options.machines.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& m : o.machines)
      list.push_back({{"machine_id", m.machine_id},
                      {"runs", m.runs},
                      {"first_run_utc", m.first_run_utc},
                      {"last_run_utc", m.last_run_utc}});
    env.results()["machines"] = list;
  } else {
    nlohmann::json per = nlohmann::json::object();
    for (const auto& [machine, recs] : o.records) {
      nlohmann::json list = nlohmann::json::array();
      for (const auto& r : recs)
        list.push_back({{"record_id", r.id},
                        {"run_utc", r.run_utc},
                        {"recorded_utc", r.recorded_utc},
                        {"command", r.command},
                        {"tool_version", r.tool_version},
                        {"source", r.source},
                        {"inputs", r.n_inputs},
                        {"quantities", r.n_quantities}});
      per[machine] = list;
    }
    env.results()["records"] = per;
  }
  return env;
}

void print_text(const HistoryListOutcome& o, std::ostream& os) {
  if (o.options.machines.empty()) {
    os << fmt::format("{:<24} {:>6}  {:<24}  {:<24}\n", "machine", "runs", "first run (UTC)", "last run (UTC)");
    for (const auto& m : o.machines)
      os << fmt::format("{:<24} {:>6}  {:<24}  {:<24}\n", m.machine_id, m.runs, m.first_run_utc, m.last_run_utc);
    if (o.machines.empty())
      os << "(no records yet: record with --record --machine-id NAME, or 'tunekit history import')\n";
    return;
  }
  for (const auto& [machine, recs] : o.records) {
    os << fmt::format("machine {}: {} records\n", machine, recs.size());
    os << fmt::format("{:>8}  {:<24}  {:<10} {:<8} {}\n", "record", "run (UTC)", "command", "tunekit", "source");
    for (const auto& r : recs)
      os << fmt::format("{:>8}  {:<24}  {:<10} {:<8} {}\n", r.id, r.run_utc, r.command, r.tool_version, r.source);
  }
}

HistoryShowOutcome compute_history_show(const HistoryOptions& a) {
  HistoryShowOutcome out;
  out.options = a;
  history::Store store(hist_db_of(a));
  out.db = store.connection().name();
  auto rec = store.get(a.record_id);
  if (!rec) throw InputError(fmt::format("no history record {}", a.record_id), out.db);
  out.record = std::move(*rec);
  try {
    out.result = nlohmann::json::parse(out.record.envelope);
  } catch (const nlohmann::json::parse_error&) {
    out.result = out.record.envelope;  // stored text that is not JSON is shown as it is
  }
  return out;
}

Envelope to_envelope(const HistoryShowOutcome& o) {
  const auto& rec = o.record;
  Envelope env("history show");
  env.set_options({{"db", o.db}, {"record_id", o.options.record_id}});
  nlohmann::json inputs = nlohmann::json::array(), quantities = nlohmann::json::object();
  for (const auto& in : rec.inputs) inputs.push_back({{"path", in.path}, {"sha256", in.sha256}, {"bytes", in.bytes}});
  for (const auto& q : rec.quantities) {
    nlohmann::json v{{"unit", q.unit}};
    if (!q.text.empty()) v["value"] = q.text;
    else {
      v["value"] = hist_number(q.value);
      v["stderr"] = hist_number(q.stderr_value);
    }
    quantities[q.name] = v;
  }
  env.results() = {{"record_id", rec.id},    {"machine_id", rec.machine_id},
                   {"run_utc", rec.run_utc}, {"recorded_utc", rec.recorded_utc},
                   {"command", rec.command}, {"tool_version", rec.tool_version},
                   {"source", rec.source},   {"result_sha256", rec.envelope_sha256},
                   {"inputs", inputs},       {"quantities", quantities},
                   {"result", o.result}};
  return env;
}

void print_text(const HistoryShowOutcome& o, std::ostream& os) {
  const auto& rec = o.record;
  os << fmt::format("record {}: machine {}, {} run at {} (recorded {}), tunekit {}\n", rec.id, rec.machine_id,
                    rec.command, rec.run_utc, rec.recorded_utc, rec.tool_version);
  if (!rec.source.empty()) os << fmt::format("source: {}\n", rec.source);
  for (const auto& in : rec.inputs) os << fmt::format("input: {}  sha256 {}\n", in.path, in.sha256);
  for (const auto& q : rec.quantities) {
    if (!q.text.empty()) os << fmt::format("{:<20} {}\n", q.name, q.text);
    else if (std::isfinite(q.stderr_value))
      os << fmt::format("{:<20} {} ± {} {}\n", q.name, display_number(q.value), display_number(q.stderr_value), q.unit);
    else os << fmt::format("{:<20} {} {}\n", q.name, display_number(q.value), q.unit);
  }
}

namespace {

struct HistoryCommand {
  HistoryOptions options;
  OutputOptions output;
};

CLI::App* hist_sub(CLI::App* parent, const std::string& name, const std::string& desc, HistoryCommand& a) {
  auto* s = parent->add_subcommand(name, desc);
  add_output_options(s, a.output, false);
  s->add_option("--db", a.options.db,
                fmt::format("SQLite file or postgresql://user@host:port/dbname (default: $TUNEKIT_HISTORY_DB, else {})",
                            kDefaultHistoryDb));
  return s;
}

}  // namespace

void register_history(CLI::App& app, CliContext& ctx) {
  auto* hist = app.add_subcommand("history",
                                  "Calibration history per machine: list, show, trend and drift, fleet report, import");
  hist->require_subcommand(1);
  hist->footer(
      "Record with any calibrate, batch or analysis command: --record --machine-id NAME [--db DB].\n"
      "The database is a SQLite file (default history.sqlite, or $TUNEKIT_HISTORY_DB) or a PostgreSQL server\n"
      "(--db postgresql://user@host:5432/tunekit) shared by a farm; its schema is created or migrated on open.");

  auto list = std::make_shared<HistoryCommand>();
  auto* l = hist_sub(hist, "list", "Machines in the history, or one machine's records (--machine)", *list);
  l->add_option("-m,--machine", list->options.machines, "Machine id (repeatable)");
  l->callback([list, &ctx] { set_exit_code(report_outcome(compute_history_list(list->options), list->output, ctx)); });

  auto show = std::make_shared<HistoryCommand>();
  auto* s = hist_sub(hist, "show", "One record: inputs with their SHA-256, quantities, the stored result", *show);
  s->add_option("id", show->options.record_id, "Record id (from 'history list --machine M')")->required();
  s->callback([show, &ctx] { set_exit_code(report_outcome(compute_history_show(show->options), show->output, ctx)); });

  auto trend = std::make_shared<HistoryCommand>();
  auto* t = hist_sub(hist, "trend", "Each quantity's runs against the machine's baseline; drift flagged", *trend);
  t->add_option("-m,--machine", trend->options.machines, "Machine id (repeatable; default: every machine)");
  t->add_option("-q,--quantity", trend->options.quantities,
                "Quantity (repeatable): tau_s, theta_s, K, x.freq_hz, x.zeta, x.shaper, x.shaper_freq_hz, pa_k_s, ...");
  t->add_option("--baseline", trend->options.drift.baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t->add_option("--coverage", trend->options.drift.coverage_k,
                "Drift when |change| > K x sqrt(u_run^2 + u_baseline^2) (1.96: 95 % interval of the difference)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t->add_flag("--runs", trend->options.show_runs, "Every run of every machine (default: every run only for --machine)");
  t->footer(
      "A change within the combined uncertainty of the run and the baseline is not drift. drift.NAME is the latest\n"
      "run's change from the baseline in percent when it is drift, 0 otherwise; gate CI on it:\n"
      "  tunekit history trend --machine printer-07 --require 'drift.x.freq_hz>-5%'\n"
      "Uncertainties follow JCGM 100:2008, Guide to the expression of uncertainty in measurement.");
  t->callback([trend, &ctx] {
    // --require is evaluated per machine by compute_history_trend(), not on the envelope.
    trend->options.require = trend->output.require;
    OutputOptions output = trend->output;
    output.require.clear();
    const auto outcome = compute_history_trend(trend->options);
    print_unmet_requirements(outcome, ctx.err);
    set_exit_code(std::max(outcome.exit_code, report_outcome(outcome, output, ctx)));
  });

  auto report = std::make_shared<HistoryCommand>();
  auto* r = hist_sub(hist, "report", "Fleet HTML report: one row per machine, sparklines, drifted quantities flagged",
                     *report);
  r->add_option("--out", report->options.html_out, "HTML file to write")->capture_default_str();
  r->add_option("-m,--machine", report->options.machines, "Machine id (repeatable; default: every machine)");
  r->add_option("-q,--quantity", report->options.quantities,
                "Columns (repeatable; default: the headline quantities present)");
  r->add_option("--baseline", report->options.drift.baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  r->add_option("--coverage", report->options.drift.coverage_k, "Coverage factor of the drift interval")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  r->callback(
      [report, &ctx] { set_exit_code(report_outcome(compute_history_report(report->options), report->output, ctx)); });

  auto imp = std::make_shared<HistoryCommand>();
  auto* i =
      hist_sub(hist, "import", "Import run directories, result files and batch summaries (folders are searched)", *imp);
  i->add_option("paths", imp->options.paths, "Run directories, result JSON files, batch summaries or folders of them")
      ->required();
  i->add_option("--machine-id", imp->options.machine_id, "The machine all these results belong to");
  i->add_flag("--machine-from-path", imp->options.machine_from_path,
              "Take each result's machine id from the first folder under PATH (archive/<machine>/...)");
  i->footer(
      "Each run directory (a folder with results.json) is one record; a batch summary is one record per dataset.\n"
      "A run's time is taken from its directory name (calibrate-YYYYMMDD-HHMMSS) or the file's time. Importing\n"
      "the same results again adds nothing. Example:\n"
      "  tunekit history import archive/ --machine-from-path --db postgresql://tunekit@farm-db/tunekit");
  i->callback([imp, &ctx] { set_exit_code(report_outcome(compute_history_import(imp->options), imp->output, ctx)); });
}

}  // namespace tunekit::cli
