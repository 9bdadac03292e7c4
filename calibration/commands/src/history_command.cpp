// tunekit history: what changed on a machine, and since when. Results recorded with
// `--record --machine-id NAME` (or imported from archived run directories and batch
// summaries) are kept per machine in a SQLite file (default) or a farm's PostgreSQL server:
//   tunekit history list    [--machine M]            machines, or one machine's records
//   tunekit history show    ID                       one record: inputs, quantities, result
//   tunekit history trend   [--machine M] [-q NAME]  each quantity against the machine's baseline
//   tunekit history report  --out fleet.html         one row per machine, sparklines, drift flagged
//   tunekit history import  PATH...                  run directories, results and batch summaries
//                                                    (history_import.cpp)
// Drift is a change from the baseline larger than the combined uncertainty of the two runs
// (tunekit/history/drift.hpp); `--require 'drift.x.freq_hz>-5%'` gates CI on it.
#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/calibration/results/history_record.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/store.hpp"

#include "history_common.hpp"

namespace tunekit::calibration {

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

}  // namespace tunekit::calibration
