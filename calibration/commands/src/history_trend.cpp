// tunekit history trend and history report: each quantity of a machine against its baseline,
// drift flagged, and the fleet's HTML report (see tunekit/calibration/commands/history_command.hpp).
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/calibration/commands/history_command.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/history/drift.hpp"
#include "tunekit/fitting/margins.hpp"
#include "tunekit/history/quantities.hpp"
#include "tunekit/history/store.hpp"
#include "tunekit/core/atomic_file.hpp"

#include "history_common.hpp"
#include "tunekit/calibration/presentation/html.hpp"

namespace tunekit::calibration {
namespace {

using history_cmd::hist_db_of;
using history_cmd::hist_machines;
using history_cmd::hist_number;

// The fleet report's page width and style sheet (tall table cells, drift flags, sparklines).
constexpr int kFleetMaxWidthPx = 1400;
std::string fleet_css() {
  return html::base_css(kFleetMaxWidthPx) +
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.3em "
         ".5em;text-align:left;vertical-align:top}\n" +
         std::string(html::kTableCss) +
         "td.drift{background:#fdecea}.flag{color:#c0392b;font-weight:bold}.small{color:#555;font-size:.85em}\n"
         "svg.spark{display:block}\n";
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
  for (std::size_t dot; (dot = name.find('.', start)) != std::string::npos; start = dot + 1)
    cur = &(*cur)[name.substr(start, dot - start)];
  (*cur)[name.substr(start)] = value;
}

// Runs as columns (one array per field, index = run - 1): a fleet's trend stays compact.
nlohmann::json hist_series_json(const history::DriftSeries& d, bool with_runs) {
  std::vector<std::int64_t> ids;
  std::vector<std::string> times, words;
  std::vector<nlohmann::json> values, errors, changes, thresholds, margins;
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
      margins.push_back(hist_number(p.margin));
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
    runs["margin"] = margins;
  }
  nlohmann::json j{{"unit", d.unit}, {"count", d.points.size()}, {"drifted", d.latest_drifted()}};
  if (d.margin.designed) j["designed_from"] = d.margin.designed_from;
  else j["margin"] = {{"kind", d.margin.kind}, {"relative", d.margin.relative}, {"basis", d.margin.basis}};
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
    j["drifted_since"] = {
        {"run", *d.drifted_since + 1}, {"record_id", p.point.record_id}, {"run_utc", p.point.run_utc}};
  } else {
    j["drifted_since"] = nullptr;
  }
  return j;
}

MachineTrend hist_trend_of(history::Store& store, const std::string& machine, const HistoryOptions& a) {
  MachineTrend t;
  t.machine_id = machine;
  std::map<std::string, std::vector<history::SeriesPoint>> all;
  if (a.quantities.empty()) all = store.series(machine);
  else
    for (const auto& q : a.quantities) all[q] = store.series(machine, q);
  // A designed quantity drifts through what it was designed from: those are analysed too.
  std::vector<history::DriftSeries> sources;
  for (const auto& q : a.quantities)
    for (const auto& from : fitting::equivalence_margin(q).designed_from)
      if (std::find(a.quantities.begin(), a.quantities.end(), from) == a.quantities.end())
        if (auto s = store.series(machine, from); !s.empty())
          sources.push_back(history::analyse_drift(from, s, a.drift));
  std::set<std::int64_t> records;
  for (const auto& name : hist_quantity_order(all, a.quantities)) {
    const auto it = all.find(name);
    if (it == all.end() || it->second.empty()) continue;
    for (const auto& p : it->second) records.insert(p.record_id);
    t.series.push_back(history::analyse_drift(name, it->second, a.drift));
  }
  const std::size_t shown = t.series.size();
  for (auto& s : sources) t.series.push_back(std::move(s));
  history::follow_designed(t.series);
  t.series.resize(shown);
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
    throw InputError(
        fmt::format("--require '{}': a threshold in % applies to drift.* (changes in percent of the baseline)", expr));
  return r;
}

}  // namespace

HistoryTrendOutcome compute_history_trend(const HistoryOptions& a) {
  HistoryTrendOutcome out;
  out.options = a;
  history::Store store(hist_db_of(a));
  out.db = store.connection().name();
  std::vector<Requirement> reqs;
  for (const auto& r : a.require) reqs.push_back(hist_parse_requirement(r));
  const auto machines = hist_machines(store, a.machines);
  if (machines.empty()) throw InputError("the history database has no records yet", out.db);
  // Named machines: every run. The whole fleet: each quantity's summary (--runs for every run).
  out.with_runs = !a.machines.empty() || a.show_runs;
  for (const auto& machine : machines) {
    HistoryTrendOutcome::Machine m;
    m.trend = hist_trend_of(store, machine, a);
    const auto& t = m.trend;
    if (t.series.empty() && !a.machines.empty())
      throw InputError(a.quantities.empty()
                           ? fmt::format("machine '{}' has no records", machine)
                           : fmt::format("machine '{}' has no records of the quantities asked for", machine),
                       out.db);
    m.quantities = nlohmann::json::object();
    m.drift = nlohmann::json::object();
    for (const auto& s : t.series) {
      m.quantities[s.name] = hist_series_json(s, out.with_runs);
      if (!s.is_text) hist_set_dotted(m.drift, s.name, s.significant_change_pct());
      if (s.latest_drifted()) m.drifted.push_back(s.name);
    }
    const nlohmann::json scope{{"drift", m.drift}, {"quantities", m.quantities}};
    for (const auto& r : reqs) {
      try {
        const auto o = evaluate_requirement(r, scope);
        m.requirements.emplace_back(r.expression, o);
        if (!o.met) out.exit_code = static_cast<int>(ExitCode::fit_failed);
      } catch (const InputError&) {
        if (machines.size() == 1) throw;
        m.requirements.emplace_back(r.expression, std::nullopt);
      }
    }
    out.machines.push_back(std::move(m));
  }
  return out;
}

Envelope to_envelope(const HistoryTrendOutcome& o) {
  const auto& a = o.options;
  Envelope env("history trend");
  env.set_options({{"db", o.db},
                   {"machines", a.machines},
                   {"quantities", a.quantities},
                   {"baseline_runs", a.drift.baseline_runs},
                   {"coverage_k", a.drift.coverage_k},
                   {"require", a.require}});
  nlohmann::json list = nlohmann::json::array();
  for (const auto& m : o.machines) {
    nlohmann::json j{{"machine_id", m.trend.machine_id}, {"runs", m.trend.runs}};
    j["quantities"] = m.quantities;
    j["drift"] = m.drift;
    j["drifted"] = m.drifted;
    if (!a.require.empty()) {
      nlohmann::json outcomes = nlohmann::json::array();
      for (const auto& [expression, r] : m.requirements) {
        if (r)
          outcomes.push_back(
              {{"expression", expression}, {"path", r->resolved_path}, {"value", r->value}, {"met", r->met}});
        else outcomes.push_back({{"expression", expression}, {"applicable", false}});
      }
      j["requirements"] = outcomes;
    }
    list.push_back(j);
  }
  env.results()["machines"] = list;
  if (o.machines.size() == 1) env.results()["drift"] = list[0]["drift"];
  return env;
}

void print_unmet_requirements(const HistoryTrendOutcome& o, std::ostream& err) {
  for (const auto& m : o.machines)
    for (const auto& [expression, r] : m.requirements)
      if (r && !r->met)
        err << fmt::format("tunekit: {}: requirement not met: {} ({} = {:.6g})\n", m.trend.machine_id, expression,
                           r->resolved_path, r->value);
}

void print_text(const HistoryTrendOutcome& o, std::ostream& os) {
  const auto& a = o.options;
  for (const auto& m : o.machines) {
    const auto& t = m.trend;
    os << fmt::format(
        "machine {}: {} runs, baseline = first {} run(s), drift: the change's interval ({:g} x combined "
        "standard error) lies beyond the quantity's margin\n",
        t.machine_id, t.runs, a.drift.baseline_runs, a.drift.coverage_k);
    for (const auto& s : t.series) {
      if (!o.with_runs) {
        const auto& p = s.points.back();
        std::string value = s.is_text ? p.point.text : display_number(p.point.value) + " " + s.unit;
        if (!s.is_text && std::isfinite(p.change_pct)) value += fmt::format(" ({:+.2f} %)", p.change_pct);
        os << fmt::format("  {:<20} {} runs, latest {}{}\n", s.name, s.points.size(), value,
                          s.drifted_since ? fmt::format("  DRIFT since run {} ({})", *s.drifted_since + 1,
                                                        s.points[*s.drifted_since].point.run_utc)
                                          : std::string());
        continue;
      }
      os << fmt::format("  {} ({})\n", s.name, s.unit);
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        const auto& p = s.points[i];
        std::string value = s.is_text ? p.point.text : display_number(p.point.value);
        if (!s.is_text && std::isfinite(p.point.stderr_value)) value += " ± " + display_number(p.point.stderr_value);
        std::string change;
        if (p.in_baseline) change = "baseline";
        else if (!s.is_text && std::isfinite(p.change_pct))
          change = s.margin.designed ? fmt::format("{:+.2f} % (designed)", p.change_pct)
                                     : fmt::format("{:+.2f} % (±{} {} noise, margin {:g} %)", p.change_pct,
                                                   display_number(p.threshold), s.unit, 100 * s.margin.relative);
        os << fmt::format("    {:>3}  {:<24}  {:<24} {:<44} {}\n", i + 1, p.point.run_utc, value, change,
                          p.drifted ? "DRIFT" : "");
      }
      if (s.drifted_since)
        os << fmt::format("    drifted since run {} ({})\n", *s.drifted_since + 1,
                          s.points[*s.drifted_since].point.run_utc);
    }
  }
}

namespace {

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
    if (s.points[i].drifted)
      dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.2\" fill=\"#c0392b\"/>", x, y);
  }
  return fmt::format(
      "<svg class=\"spark\" width=\"{:g}\" height=\"{:g}\" viewBox=\"0 0 {:g} {:g}\" role=\"img\">"
      "<polyline fill=\"none\" stroke=\"#2c5d8a\" stroke-width=\"1.3\" points=\"{}\"/>{}</svg>",
      w, h, w, h, pts, dots);
}

}  // namespace

HistoryReportOutcome compute_history_report(const HistoryOptions& a) {
  HistoryReportOutcome out;
  out.options = a;
  history::Store store(hist_db_of(a));
  out.db = store.connection().name();
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
  h << html::head("tunekit fleet report", fleet_css());
  h << "<h1>tunekit fleet report</h1>\n";
  h << fmt::format(
      "<p>{} machines, database {}. A quantity is flagged when the interval of its latest run's change from the "
      "machine's baseline (first {} run(s)), {:g} times the combined standard error either side, lies wholly "
      "beyond the quantity's equivalence margin (resonance frequency 1 %, damping ratio 10 %, time constant 2 %, "
      "gain 2 %, dead time 5 %); a designed setting is flagged only when what it was designed from is.</p>\n",
      machines.size(), html::escape(store.connection().name()), a.drift.baseline_runs, a.drift.coverage_k);
  h << "<table id=\"fleet\">\n<tr><th>machine</th><th>runs</th><th>last run (UTC)</th>";
  for (const auto& c : columns) h << "<th>" << html::escape(c) << "</th>";
  h << "<th>drifted</th></tr>\n";
  for (const auto& t : trends) {
    std::string last;
    std::vector<std::string> drifted;
    for (const auto& s : t.series) {
      if (!s.points.empty()) last = std::max(last, s.points.back().point.run_utc);
      if (s.latest_drifted()) drifted.push_back(s.name);
    }
    h << "<tr data-machine=\"" << html::escape(t.machine_id) << "\"><td>" << html::escape(t.machine_id)
      << "</td><td class=\"num\">" << t.runs << "</td><td>" << html::escape(last) << "</td>";
    for (const auto& c : columns) {
      const auto it = std::find_if(t.series.begin(), t.series.end(), [&](const auto& s) { return s.name == c; });
      if (it == t.series.end() || it->points.empty()) {
        h << "<td></td>";
        continue;
      }
      const auto& p = it->points.back();
      const std::string value = it->is_text ? p.point.text : display_number(p.point.value) + " " + it->unit;
      h << "<td" << (p.drifted ? " class=\"drift\" data-drifted=\"1\"" : "") << ">" << hist_sparkline(*it)
        << html::escape(value);
      if (!it->is_text && !p.in_baseline && std::isfinite(p.change_pct))
        h << fmt::format(" <span class=\"small\">({:+.1f} %)</span>", p.change_pct);
      if (p.drifted && it->drifted_since)
        h << "<br><span class=\"flag\">drift since " << html::escape(it->points[*it->drifted_since].point.run_utc)
          << "</span>";
      h << "</td>";
    }
    std::string dl;
    for (const auto& d : drifted) dl += (dl.empty() ? "" : ", ") + d;
    h << "<td>" << (drifted.empty() ? "" : "<span class=\"flag\">" + html::escape(dl) + "</span>") << "</td></tr>\n";
    out.rows.push_back({t.machine_id, t.runs, last, drifted});
  }
  h << "</table>\n</body>\n</html>\n";
  core::write_file_atomic(a.html_out, h.str());

  out.columns = columns;
  return out;
}

Envelope to_envelope(const HistoryReportOutcome& o) {
  Envelope env("history report");
  env.set_options({{"db", o.db}, {"out", o.options.html_out}, {"quantities", o.columns}});
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : o.rows)
    rows.push_back(
        {{"machine_id", r.machine_id}, {"runs", r.runs}, {"last_run_utc", r.last_run_utc}, {"drifted", r.drifted}});
  env.results()["machines"] = rows;
  env.results()["report"] = o.options.html_out;
  return env;
}

void print_text(const HistoryReportOutcome& o, std::ostream& os) {
  os << fmt::format("report: {}\n", o.options.html_out);
}

}  // namespace tunekit::calibration
