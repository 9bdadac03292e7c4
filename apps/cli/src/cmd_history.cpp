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
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/history_record.hpp"
#include "tunekit/cli/report.hpp"
#include "tunekit/cli/requirements.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/drift.hpp"
#include "tunekit/history/quantities.hpp"
#include "tunekit/history/store.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/protocols/atomic_file.hpp"

#include "history_args.hpp"

namespace tunekit::cli {
namespace {

namespace fs = std::filesystem;

using history_cmd::HistoryArgs;
using history_cmd::hist_run_import;

nlohmann::json hist_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::string hist_html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// Machines to look at: those given, or every machine in the database.
std::vector<std::string> hist_machines(history::Store& store, const std::vector<std::string>& given) {
  if (!given.empty()) {
    for (const auto& m : given) history::check_machine_id(m);
    return given;
  }
  std::vector<std::string> out;
  for (const auto& m : store.machines()) out.push_back(m.machine_id);
  return out;
}

// The quantities to show: those asked for, else the headline ones first, then the rest by name.
std::vector<std::string> hist_quantity_order(const std::map<std::string, std::vector<history::SeriesPoint>>& series,
                                             const std::vector<std::string>& asked) {
  if (!asked.empty()) return asked;
  std::vector<std::string> out;
  for (const auto& h : history::headline_quantities())
    if (series.count(h)) out.push_back(h);
  for (const auto& [name, s] : series)
    if (std::find(out.begin(), out.end(), name) == out.end()) out.push_back(name);
  return out;
}

// Puts `value` at the dotted `name` inside `obj` ("x.freq_hz" -> obj.x.freq_hz).
void hist_set_dotted(nlohmann::json& obj, const std::string& name, const nlohmann::json& value) {
  nlohmann::json* cur = &obj;
  std::size_t start = 0;
  for (std::size_t dot; (dot = name.find('.', start)) != std::string::npos; start = dot + 1) cur = &(*cur)[name.substr(start, dot - start)];
  (*cur)[name.substr(start)] = value;
}

// Runs as columns (one array per field, index = run - 1): a fleet's trend stays compact.
nlohmann::json hist_series_json(const history::DriftSeries& d, bool with_runs) {
  std::vector<std::int64_t> ids;
  std::vector<std::string> times, words;
  std::vector<nlohmann::json> values, errors, changes, thresholds;
  std::vector<bool> drifted;
  for (const auto& p : d.points) {
    ids.push_back(p.point.record_id);
    times.push_back(p.point.run_utc);
    drifted.push_back(p.drifted);
    if (d.is_text) {
      words.push_back(p.point.text);
    } else {
      values.push_back(hist_number(p.point.value));
      errors.push_back(hist_number(p.point.stderr_value));
      changes.push_back(hist_number(p.change_pct));
      thresholds.push_back(hist_number(p.threshold));
    }
  }
  nlohmann::json runs{{"record_id", ids}, {"run_utc", times}, {"drifted", drifted}};
  if (d.is_text) {
    runs["value"] = words;
  } else {
    runs["value"] = values;
    runs["stderr"] = errors;
    runs["change_pct"] = changes;
    runs["threshold"] = thresholds;
  }
  nlohmann::json j{{"unit", d.unit}, {"count", d.points.size()}, {"drifted", d.latest_drifted()}};
  if (with_runs) j["runs"] = runs;
  if (!d.points.empty()) {
    const auto& last = d.points.back();
    j["latest"] = {{"record_id", last.point.record_id}, {"run_utc", last.point.run_utc}};
    if (d.is_text) j["latest"]["value"] = last.point.text;
    else {
      j["latest"]["value"] = hist_number(last.point.value);
      j["latest"]["stderr"] = hist_number(last.point.stderr_value);
    }
  }
  if (d.is_text) {
    j["baseline"] = d.baseline_text;
  } else {
    j["baseline"] = hist_number(d.baseline);
    j["baseline_stderr"] = hist_number(d.baseline_stderr);
    j["latest_change_pct"] = d.points.empty() ? nlohmann::json(nullptr) : hist_number(d.points.back().change_pct);
    j["drift_pct"] = d.significant_change_pct();
  }
  if (d.drifted_since) {
    const auto& p = d.points[*d.drifted_since];
    j["drifted_since"] = {{"run", *d.drifted_since + 1}, {"record_id", p.point.record_id}, {"run_utc", p.point.run_utc}};
  } else {
    j["drifted_since"] = nullptr;
  }
  return j;
}

struct MachineTrend {
  std::string machine_id;
  std::size_t runs = 0;
  std::vector<history::DriftSeries> series;
};

MachineTrend hist_trend_of(history::Store& store, const std::string& machine, const HistoryArgs& a) {
  MachineTrend t;
  t.machine_id = machine;
  std::map<std::string, std::vector<history::SeriesPoint>> all;
  if (a.quantities.empty()) all = store.series(machine);
  else
    for (const auto& q : a.quantities) all[q] = store.series(machine, q);
  const history::DriftOptions opt{a.baseline_runs, a.coverage_k};
  std::set<std::int64_t> records;
  for (const auto& name : hist_quantity_order(all, a.quantities)) {
    const auto it = all.find(name);
    if (it == all.end() || it->second.empty()) continue;
    for (const auto& p : it->second) records.insert(p.record_id);
    t.series.push_back(history::analyse_drift(name, it->second, opt));
  }
  t.runs = records.size();
  return t;
}

// --require on drift: a trailing % says the threshold is in percent, which drift.* values are.
Requirement hist_parse_requirement(const std::string& expr) {
  std::string e = expr;
  while (!e.empty() && e.back() == ' ') e.pop_back();
  const bool pct = !e.empty() && e.back() == '%';
  if (pct) e.pop_back();
  Requirement r = parse_requirement(e);
  r.expression = expr;
  if (pct && r.path.rfind("drift.", 0) != 0)
    throw InputError(fmt::format("--require '{}': a threshold in % applies to drift.* (changes in percent of the baseline)", expr));
  return r;
}

// ---------------------------------------------------------------------------------------------

int hist_run_list(const HistoryArgs& a, CliContext& ctx) {
  const std::string db = history_db(a.output);
  history::Store store(db);
  Envelope env("history list");
  env.set_options({{"db", store.connection().name()}, {"machines", a.machines}});
  if (a.machines.empty()) {
    nlohmann::json list = nlohmann::json::array();
    const auto machines = store.machines();
    for (const auto& m : machines)
      list.push_back({{"machine_id", m.machine_id}, {"runs", m.runs}, {"first_run_utc", m.first_run_utc},
                      {"last_run_utc", m.last_run_utc}});
    env.results()["machines"] = list;
    if (!a.output.json) {
      ctx.out << fmt::format("{:<24} {:>6}  {:<24}  {:<24}\n", "machine", "runs", "first run (UTC)", "last run (UTC)");
      for (const auto& m : machines)
        ctx.out << fmt::format("{:<24} {:>6}  {:<24}  {:<24}\n", m.machine_id, m.runs, m.first_run_utc, m.last_run_utc);
      if (machines.empty()) ctx.out << "(no records yet: record with --record --machine-id NAME, or 'tunekit history import')\n";
    }
  } else {
    nlohmann::json per = nlohmann::json::object();
    for (const auto& machine : hist_machines(store, a.machines)) {
      nlohmann::json list = nlohmann::json::array();
      const auto recs = store.records(machine);
      for (const auto& r : recs)
        list.push_back({{"record_id", r.id}, {"run_utc", r.run_utc}, {"recorded_utc", r.recorded_utc}, {"command", r.command},
                        {"tool_version", r.tool_version}, {"source", r.source}, {"inputs", r.n_inputs},
                        {"quantities", r.n_quantities}});
      per[machine] = list;
      if (!a.output.json) {
        ctx.out << fmt::format("machine {}: {} records\n", machine, recs.size());
        ctx.out << fmt::format("{:>8}  {:<24}  {:<10} {:<8} {}\n", "record", "run (UTC)", "command", "tunekit", "source");
        for (const auto& r : recs)
          ctx.out << fmt::format("{:>8}  {:<24}  {:<10} {:<8} {}\n", r.id, r.run_utc, r.command, r.tool_version, r.source);
      }
    }
    env.results()["records"] = per;
  }
  OutputOptions o = a.output;
  return emit(env, o, ctx);
}

int hist_run_show(const HistoryArgs& a, CliContext& ctx) {
  history::Store store(history_db(a.output));
  const auto rec = store.get(a.record_id);
  if (!rec) throw InputError(fmt::format("no history record {}", a.record_id), store.connection().name());
  Envelope env("history show");
  env.set_options({{"db", store.connection().name()}, {"record_id", a.record_id}});
  nlohmann::json inputs = nlohmann::json::array(), quantities = nlohmann::json::object();
  for (const auto& in : rec->inputs) inputs.push_back({{"path", in.path}, {"sha256", in.sha256}, {"bytes", in.bytes}});
  for (const auto& q : rec->quantities) {
    nlohmann::json v{{"unit", q.unit}};
    if (!q.text.empty()) v["value"] = q.text;
    else {
      v["value"] = hist_number(q.value);
      v["stderr"] = hist_number(q.stderr_value);
    }
    quantities[q.name] = v;
  }
  nlohmann::json result;
  try {
    result = nlohmann::json::parse(rec->envelope);
  } catch (const nlohmann::json::parse_error&) {
    result = rec->envelope;  // stored text that is not JSON is shown as it is
  }
  env.results() = {{"record_id", rec->id},          {"machine_id", rec->machine_id}, {"run_utc", rec->run_utc},
                   {"recorded_utc", rec->recorded_utc}, {"command", rec->command},   {"tool_version", rec->tool_version},
                   {"source", rec->source},          {"result_sha256", rec->envelope_sha256},
                   {"inputs", inputs},               {"quantities", quantities},     {"result", result}};
  if (!a.output.json) {
    ctx.out << fmt::format("record {}: machine {}, {} run at {} (recorded {}), tunekit {}\n", rec->id, rec->machine_id,
                           rec->command, rec->run_utc, rec->recorded_utc, rec->tool_version);
    if (!rec->source.empty()) ctx.out << fmt::format("source: {}\n", rec->source);
    for (const auto& in : rec->inputs) ctx.out << fmt::format("input: {}  sha256 {}\n", in.path, in.sha256);
    for (const auto& q : rec->quantities) {
      if (!q.text.empty()) ctx.out << fmt::format("{:<20} {}\n", q.name, q.text);
      else if (std::isfinite(q.stderr_value))
        ctx.out << fmt::format("{:<20} {} ± {} {}\n", q.name, display_number(q.value), display_number(q.stderr_value), q.unit);
      else
        ctx.out << fmt::format("{:<20} {} {}\n", q.name, display_number(q.value), q.unit);
    }
  }
  return emit(env, a.output, ctx);
}

int hist_run_trend(const HistoryArgs& a, CliContext& ctx) {
  history::Store store(history_db(a.output));
  std::vector<Requirement> reqs;
  for (const auto& r : a.output.require) reqs.push_back(hist_parse_requirement(r));
  const auto machines = hist_machines(store, a.machines);
  if (machines.empty()) throw InputError("the history database has no records yet", store.connection().name());

  Envelope env("history trend");
  env.set_options({{"db", store.connection().name()}, {"machines", a.machines}, {"quantities", a.quantities},
                   {"baseline_runs", a.baseline_runs}, {"coverage_k", a.coverage_k}, {"require", a.output.require}});
  nlohmann::json list = nlohmann::json::array();
  int code = 0;
  // Named machines: every run. The whole fleet: each quantity's summary (--runs for every run).
  const bool with_runs = !a.machines.empty() || a.show_runs;
  for (const auto& machine : machines) {
    const auto t = hist_trend_of(store, machine, a);
    if (t.series.empty() && !a.machines.empty())
      throw InputError(a.quantities.empty() ? fmt::format("machine '{}' has no records", machine)
                                            : fmt::format("machine '{}' has no records of the quantities asked for", machine),
                       store.connection().name());
    nlohmann::json m{{"machine_id", machine}, {"runs", t.runs}};
    nlohmann::json qs = nlohmann::json::object(), drift = nlohmann::json::object();
    std::vector<std::string> drifted;
    for (const auto& s : t.series) {
      qs[s.name] = hist_series_json(s, with_runs);
      if (!s.is_text) hist_set_dotted(drift, s.name, s.significant_change_pct());
      if (s.latest_drifted()) drifted.push_back(s.name);
    }
    m["quantities"] = qs;
    m["drift"] = drift;
    m["drifted"] = drifted;
    if (!reqs.empty()) {
      nlohmann::json outcomes = nlohmann::json::array();
      const nlohmann::json scope{{"drift", drift}, {"quantities", qs}};
      for (const auto& r : reqs) {
        try {
          const auto o = evaluate_requirement(r, scope);
          outcomes.push_back({{"expression", r.expression}, {"path", o.resolved_path}, {"value", o.value}, {"met", o.met}});
          if (!o.met) {
            code = static_cast<int>(ExitCode::fit_failed);
            ctx.err << fmt::format("tunekit: {}: requirement not met: {} ({} = {:.6g})\n", machine, r.expression,
                                   o.resolved_path, o.value);
          }
        } catch (const InputError&) {
          if (machines.size() == 1) throw;
          outcomes.push_back({{"expression", r.expression}, {"applicable", false}});
        }
      }
      m["requirements"] = outcomes;
    }
    list.push_back(m);

    if (!a.output.json) {
      ctx.out << fmt::format("machine {}: {} runs, baseline = first {} run(s), drift beyond {:g} x combined standard error\n",
                             machine, t.runs, a.baseline_runs, a.coverage_k);
      for (const auto& s : t.series) {
        if (!with_runs) {
          const auto& p = s.points.back();
          std::string value = s.is_text ? p.point.text : display_number(p.point.value) + " " + s.unit;
          if (!s.is_text && std::isfinite(p.change_pct)) value += fmt::format(" ({:+.2f} %)", p.change_pct);
          ctx.out << fmt::format("  {:<20} {} runs, latest {}{}\n", s.name, s.points.size(), value,
                                 s.drifted_since ? fmt::format("  DRIFT since run {} ({})", *s.drifted_since + 1,
                                                               s.points[*s.drifted_since].point.run_utc)
                                                 : std::string());
          continue;
        }
        ctx.out << fmt::format("  {} ({})\n", s.name, s.unit);
        for (std::size_t i = 0; i < s.points.size(); ++i) {
          const auto& p = s.points[i];
          std::string value = s.is_text ? p.point.text : display_number(p.point.value);
          if (!s.is_text && std::isfinite(p.point.stderr_value)) value += " ± " + display_number(p.point.stderr_value);
          std::string change;
          if (p.in_baseline) change = "baseline";
          else if (!s.is_text && std::isfinite(p.change_pct))
            change = fmt::format("{:+.2f} % (limit ±{} {})", p.change_pct, display_number(p.threshold), s.unit);
          ctx.out << fmt::format("    {:>3}  {:<24}  {:<24} {:<28} {}\n", i + 1, p.point.run_utc, value, change,
                                 p.drifted ? "DRIFT" : "");
        }
        if (s.drifted_since)
          ctx.out << fmt::format("    drifted since run {} ({})\n", *s.drifted_since + 1, s.points[*s.drifted_since].point.run_utc);
      }
    }
  }
  env.results()["machines"] = list;
  if (machines.size() == 1) env.results()["drift"] = list[0]["drift"];
  OutputOptions o = a.output;
  o.require.clear();  // evaluated per machine above
  return std::max(code, emit(env, o, ctx));
}

// A small inline SVG line of a series; drifted runs are red dots.
std::string hist_sparkline(const history::DriftSeries& s) {
  if (s.is_text || s.points.empty()) return "";
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& p : s.points)
    if (std::isfinite(p.point.value)) {
      lo = std::min(lo, p.point.value);
      hi = std::max(hi, p.point.value);
    }
  if (!std::isfinite(lo)) return "";
  const double w = 120, h = 28, pad = 3;
  const double span = hi > lo ? hi - lo : 1;
  const std::size_t n = s.points.size();
  auto xy = [&](std::size_t i) {
    const double x = n > 1 ? pad + (w - 2 * pad) * static_cast<double>(i) / static_cast<double>(n - 1) : w / 2;
    const double y = hi > lo ? h - pad - (h - 2 * pad) * (s.points[i].point.value - lo) / span : h / 2;
    return std::pair{x, y};
  };
  std::string pts, dots;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(s.points[i].point.value)) continue;
    const auto [x, y] = xy(i);
    pts += fmt::format("{:.1f},{:.1f} ", x, y);
    if (s.points[i].drifted) dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.2\" fill=\"#c0392b\"/>", x, y);
  }
  return fmt::format("<svg class=\"spark\" width=\"{:g}\" height=\"{:g}\" viewBox=\"0 0 {:g} {:g}\" role=\"img\">"
                     "<polyline fill=\"none\" stroke=\"#2c5d8a\" stroke-width=\"1.3\" points=\"{}\"/>{}</svg>",
                     w, h, w, h, pts, dots);
}

int hist_run_report(const HistoryArgs& a, CliContext& ctx) {
  history::Store store(history_db(a.output));
  const auto machines = hist_machines(store, a.machines);
  if (machines.empty()) throw InputError("the history database has no records yet", store.connection().name());
  std::vector<MachineTrend> trends;
  std::vector<std::string> columns = a.quantities;
  std::set<std::string> present;
  for (const auto& m : machines) {
    trends.push_back(hist_trend_of(store, m, a));
    for (const auto& s : trends.back().series) present.insert(s.name);
  }
  if (columns.empty())
    for (const auto& h : history::headline_quantities())
      if (present.count(h)) columns.push_back(h);

  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<title>tunekit fleet report</title>\n<style>\n"
    << "body{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;margin:2em auto;max-width:1400px;color:#222}\n"
    << "h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}\n"
    << "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.3em .5em;text-align:left;vertical-align:top}\n"
    << "td.num{text-align:right;font-variant-numeric:tabular-nums}th{background:#f2f2f2}\n"
    << "td.drift{background:#fdecea}.flag{color:#c0392b;font-weight:bold}.small{color:#555;font-size:.85em}\n"
    << "svg.spark{display:block}\n</style>\n</head>\n<body>\n";
  h << "<h1>tunekit fleet report</h1>\n";
  h << fmt::format("<p>{} machines, database {}. A quantity is flagged when its latest run differs from the machine's "
                   "baseline (first {} run(s)) by more than {:g} times the combined standard error.</p>\n",
                   machines.size(), hist_html_escape(store.connection().name()), a.baseline_runs, a.coverage_k);
  h << "<table id=\"fleet\">\n<tr><th>machine</th><th>runs</th><th>last run (UTC)</th>";
  for (const auto& c : columns) h << "<th>" << hist_html_escape(c) << "</th>";
  h << "<th>drifted</th></tr>\n";
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& t : trends) {
    std::string last;
    std::vector<std::string> drifted;
    for (const auto& s : t.series) {
      if (!s.points.empty()) last = std::max(last, s.points.back().point.run_utc);
      if (s.latest_drifted()) drifted.push_back(s.name);
    }
    h << "<tr data-machine=\"" << hist_html_escape(t.machine_id) << "\"><td>" << hist_html_escape(t.machine_id) << "</td><td class=\"num\">"
      << t.runs << "</td><td>" << hist_html_escape(last) << "</td>";
    for (const auto& c : columns) {
      const auto it = std::find_if(t.series.begin(), t.series.end(), [&](const auto& s) { return s.name == c; });
      if (it == t.series.end() || it->points.empty()) {
        h << "<td></td>";
        continue;
      }
      const auto& p = it->points.back();
      const std::string value = it->is_text ? p.point.text : display_number(p.point.value) + " " + it->unit;
      h << "<td" << (p.drifted ? " class=\"drift\" data-drifted=\"1\"" : "") << ">" << hist_sparkline(*it)
        << hist_html_escape(value);
      if (!it->is_text && !p.in_baseline && std::isfinite(p.change_pct))
        h << fmt::format(" <span class=\"small\">({:+.1f} %)</span>", p.change_pct);
      if (p.drifted && it->drifted_since)
        h << "<br><span class=\"flag\">drift since " << hist_html_escape(it->points[*it->drifted_since].point.run_utc)
          << "</span>";
      h << "</td>";
    }
    std::string dl;
    for (const auto& d : drifted) dl += (dl.empty() ? "" : ", ") + d;
    h << "<td>" << (drifted.empty() ? "" : "<span class=\"flag\">" + hist_html_escape(dl) + "</span>") << "</td></tr>\n";
    rows.push_back({{"machine_id", t.machine_id}, {"runs", t.runs}, {"last_run_utc", last}, {"drifted", drifted}});
  }
  h << "</table>\n</body>\n</html>\n";
  protocols::write_file_atomic(a.html_out, h.str());

  Envelope env("history report");
  env.set_options({{"db", store.connection().name()}, {"out", a.html_out}, {"quantities", columns}});
  env.results()["machines"] = rows;
  env.results()["report"] = a.html_out;
  if (!a.output.json) ctx.out << fmt::format("report: {}\n", a.html_out);
  return emit(env, a.output, ctx);
}

CLI::App* hist_sub(CLI::App* parent, const std::string& name, const std::string& desc, HistoryArgs& a) {
  auto* s = parent->add_subcommand(name, desc);
  add_output_options(s, a.output, false);
  s->add_option("--db", a.output.db,
                fmt::format("SQLite file or postgresql://user@host:port/dbname (default: $TUNEKIT_HISTORY_DB, else {})",
                            kDefaultHistoryDb));
  return s;
}

}  // namespace

void register_history(CLI::App& app, CliContext& ctx) {
  auto* hist = app.add_subcommand("history", "Calibration history per machine: list, show, trend and drift, fleet report, import");
  hist->require_subcommand(1);
  hist->footer(
      "Record with any calibrate, batch or analysis command: --record --machine-id NAME [--db DB].\n"
      "The database is a SQLite file (default history.sqlite, or $TUNEKIT_HISTORY_DB) or a PostgreSQL server\n"
      "(--db postgresql://user@host:5432/tunekit) shared by a farm; its schema is created or migrated on open.");

  auto list = std::make_shared<HistoryArgs>();
  auto* l = hist_sub(hist, "list", "Machines in the history, or one machine's records (--machine)", *list);
  l->add_option("-m,--machine", list->machines, "Machine id (repeatable)");
  l->callback([list, &ctx] { set_exit_code(hist_run_list(*list, ctx)); });

  auto show = std::make_shared<HistoryArgs>();
  auto* s = hist_sub(hist, "show", "One record: inputs with their SHA-256, quantities, the stored result", *show);
  s->add_option("id", show->record_id, "Record id (from 'history list --machine M')")->required();
  s->callback([show, &ctx] { set_exit_code(hist_run_show(*show, ctx)); });

  auto trend = std::make_shared<HistoryArgs>();
  auto* t = hist_sub(hist, "trend", "Each quantity's runs against the machine's baseline; drift flagged", *trend);
  t->add_option("-m,--machine", trend->machines, "Machine id (repeatable; default: every machine)");
  t->add_option("-q,--quantity", trend->quantities,
                "Quantity (repeatable): tau_s, theta_s, K, x.freq_hz, x.zeta, x.shaper, x.shaper_freq_hz, pa_k_s, ...");
  t->add_option("--baseline", trend->baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t->add_option("--coverage", trend->coverage_k,
                "Drift when |change| > K x sqrt(u_run^2 + u_baseline^2) (1.96: 95 % interval of the difference)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  t->add_flag("--runs", trend->show_runs, "Every run of every machine (default: every run only for --machine)");
  t->footer(
      "A change within the combined uncertainty of the run and the baseline is not drift. drift.NAME is the latest\n"
      "run's change from the baseline in percent when it is drift, 0 otherwise; gate CI on it:\n"
      "  tunekit history trend --machine printer-07 --require 'drift.x.freq_hz>-5%'\n"
      "Uncertainties follow JCGM 100:2008, Guide to the expression of uncertainty in measurement.");
  t->callback([trend, &ctx] { set_exit_code(hist_run_trend(*trend, ctx)); });

  auto report = std::make_shared<HistoryArgs>();
  auto* r = hist_sub(hist, "report", "Fleet HTML report: one row per machine, sparklines, drifted quantities flagged", *report);
  r->add_option("--out", report->html_out, "HTML file to write")->capture_default_str();
  r->add_option("-m,--machine", report->machines, "Machine id (repeatable; default: every machine)");
  r->add_option("-q,--quantity", report->quantities, "Columns (repeatable; default: the headline quantities present)");
  r->add_option("--baseline", report->baseline_runs, "The machine's first N runs form its baseline")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  r->add_option("--coverage", report->coverage_k, "Coverage factor of the drift interval")->capture_default_str()->check(CLI::PositiveNumber);
  r->callback([report, &ctx] { set_exit_code(hist_run_report(*report, ctx)); });

  auto imp = std::make_shared<HistoryArgs>();
  auto* i = hist_sub(hist, "import", "Import run directories, result files and batch summaries (folders are searched)", *imp);
  i->add_option("paths", imp->paths, "Run directories, result JSON files, batch summaries or folders of them")->required();
  i->add_option("--machine-id", imp->output.machine_id, "The machine all these results belong to");
  i->add_flag("--machine-from-path", imp->machine_from_path,
              "Take each result's machine id from the first folder under PATH (archive/<machine>/...)");
  i->footer(
      "Each run directory (a folder with results.json) is one record; a batch summary is one record per dataset.\n"
      "A run's time is taken from its directory name (calibrate-YYYYMMDD-HHMMSS) or the file's time. Importing\n"
      "the same results again adds nothing. Example:\n"
      "  tunekit history import archive/ --machine-from-path --db postgresql://tunekit@farm-db/tunekit");
  i->callback([imp, &ctx] { set_exit_code(hist_run_import(*imp, ctx)); });
}

}  // namespace tunekit::cli
