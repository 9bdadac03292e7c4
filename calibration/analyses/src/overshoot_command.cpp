// tunekit overshoot: axis overshoot and settling at the corners of the axis-rectangle protocol
// (Hemminger, "Improvements and Characterization of Error, Speed, and Capabilities in Low-Cost
// Additive Manufacturing Systems", MS thesis, UCLA, 2022), from a run directory or a CSV; and a
// grid mode that runs the protocol over lists of speeds and accelerations and maps overshoot,
// completion time and the thesis's figure of merit.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/overshoot_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/analyses/simulated_machine.hpp"
#include "tunekit/calibration/presentation/report_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/core/version.hpp"
#include "tunekit/protocols/stop_signals.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/overshoot.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::calibration {
namespace {

std::vector<std::string> overshoot_files_matching(const std::string& dir, const std::string& prefix) {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().extension() == ".csv") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

ident::OvershootAnalysis overshoot_from_run_dir(const std::string& dir, const ident::OvershootOptions& o,
                                                std::vector<InputDigest>* inputs) {
  const auto raw = overshoot_files_matching(dir, "raw_data_");
  const auto cmd = overshoot_files_matching(dir, "commanded_accel_");
  if (raw.size() != 1 || cmd.size() != 1)
    throw InputError(fmt::format("a run directory of axis-rectangle needs one raw_data_*.csv and one "
                                 "commanded_accel_*.csv (found {} and {})",
                                 raw.size(), cmd.size()),
                     dir);
  formats::CsvOptions ro;
  ro.columns = {"time", "accel_x", "accel_y"};
  ro.time_column = "time";
  const InputFile raw_file = InputFile::read(raw[0]);
  const auto a = formats::parse_csv(raw_file.bytes(), raw[0], ro);
  formats::CsvOptions co;
  co.columns = {"time", "accel_x", "accel_y"};
  co.time_column = "time";
  const InputFile cmd_file = InputFile::read(cmd[0]);
  const auto c = formats::parse_csv(cmd_file.bytes(), cmd[0], co);
  if (a.rows != c.rows)
    throw InputError(fmt::format("{} has {} rows but {} has {}: not one time base", raw[0], a.rows, cmd[0], c.rows),
                     dir);
  if (inputs) *inputs = {raw_file.digest(), cmd_file.digest()};
  try {
    return ident::analyze_overshoot_accel(a.column("time").values, a.column("accel_x").values,
                                          a.column("accel_y").values, c.column("accel_x").values,
                                          c.column("accel_y").values, o);
  } catch (const Error& e) {
    if (!e.location().empty()) throw;
    throw InputError(e.message(), raw[0]);
  }
}

ident::OvershootAnalysis overshoot_from_csv(const OvershootOptions& a, std::vector<InputDigest>& inputs) {
  formats::CsvOptions co;
  co.time_column = a.time_column;
  co.columns = {a.time_column};
  const bool position = !a.pos_x.empty() || !a.pos_y.empty();
  if (position) {
    if (!a.pos_x.empty()) co.columns.push_back(a.pos_x);
    if (!a.pos_y.empty()) co.columns.push_back(a.pos_y);
  } else {
    if (a.cmd_x.empty() || a.cmd_y.empty())
      throw InputError(
          "a CSV needs --position-x/--position-y (encoder, mm) or --cmd-x and --cmd-y (commanded "
          "acceleration, mm/s^2) with the accelerometer columns");
    co.columns.insert(co.columns.end(), {a.accel_x, a.accel_y, a.cmd_x, a.cmd_y});
  }
  const InputFile file = InputFile::read(a.input);
  const auto t = formats::parse_csv(file.bytes(), a.input, co);
  inputs = {file.digest()};
  try {
    if (position)
      return ident::analyze_overshoot_position(
          t.column(a.time_column).values, a.pos_x.empty() ? std::vector<double>{} : t.column(a.pos_x).values,
          a.pos_y.empty() ? std::vector<double>{} : t.column(a.pos_y).values, a.analysis);
    return ident::analyze_overshoot_accel(t.column(a.time_column).values, t.column(a.accel_x).values,
                                          t.column(a.accel_y).values, t.column(a.cmd_x).values,
                                          t.column(a.cmd_y).values, a.analysis);
  } catch (const Error& e) {
    if (!e.location().empty()) throw;
    throw InputError(e.message(), a.input);
  }
}

void print_overshoot_analysis(std::ostream& os, const ident::OvershootAnalysis& r) {
  os << fmt::format("{} corners from the {}; motion time {:.3f} s\n", r.corners.size(), r.source, r.motion_time_s);
  os << "  corner axis   move_mm  overshoot_mm     %   settle_s  resid_mm  resid_Hz\n";
  for (const auto& c : r.corners)
    os << fmt::format("  {:>6} {:>4} {:>9.2f} {:>13.4f} {:>5.3f} {:>10.4f}{} {:>8.4f} {:>9.1f}\n", c.index, c.axis,
                      c.move_mm, c.overshoot_mm, c.overshoot_pct, c.settling_time_s, c.settled ? ' ' : '*',
                      c.residual_amplitude_mm, c.residual_freq_hz);
  for (const auto& s : r.axes)
    os << fmt::format(
        "  axis {}: mean overshoot {:.4f} mm (max {:.4f}), mean settling {:.4f} s, residual {:.4f} mm at "
        "{:.1f} Hz\n",
        s.axis, s.mean_overshoot_mm, s.max_overshoot_mm, s.mean_settling_time_s, s.mean_residual_amplitude_mm,
        s.median_residual_freq_hz);
}

std::vector<double> parse_overshoot_grid_list(const std::string& name, const std::string& v) {
  std::vector<double> out;
  std::size_t b = 0;
  for (;;) {
    const auto e = v.find(',', b);
    const std::string item = v.substr(b, e == std::string::npos ? std::string::npos : e - b);
    const auto d = core::parse_decimal(item);
    if (!d || !std::isfinite(*d))
      throw InputError(fmt::format("-p {}: '{}' is not a decimal number (such as 12, 0.5 or 1e-3)", name, item));
    out.push_back(*d);
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return out;
}

OvershootGrid compute_overshoot_grid(const OvershootOptions& a, OvershootOutcome& outcome, std::ostream* progress) {
  OvershootGrid g;
  auto& lists = g.lists;
  for (const auto& p : a.params) {
    const auto eq = p.find('=');
    if (eq == std::string::npos) throw InputError(fmt::format("-p {}: expected NAME=VALUE[,VALUE...]", p));
    lists[p.substr(0, eq)] = parse_overshoot_grid_list(p.substr(0, eq), p.substr(eq + 1));
  }
  // The machine of every grid run: its profile loaded, the simulator's options read, once.
  protocols::RunOptions machine_run = a.run;
  load_run_machine(machine_run, "", a.sim_options);
  if (!lists.count("speed_mm_s") || !lists.count("accel_mm_s2")) {
    // The rectangle's defaults come from the machine's limits: its dry run on this machine.
    protocols::RunOptions dry = machine_run;
    dry.protocol = "axis-rectangle";
    dry.dry_run = true;
    for (const auto& [k, vals] : lists) dry.params[k] = vals.front();
    const auto defaults = protocols::run_experiment(dry).experiment.params;
    for (const char* k : {"speed_mm_s", "accel_mm_s2"})
      if (!lists.count(k)) lists[k] = {defaults.at(k)};
  }
  for (const auto& [k, v] : lists)
    if (k != "speed_mm_s" && k != "accel_mm_s2" && v.size() != 1)
      throw InputError(fmt::format("-p {}: only speed_mm_s and accel_mm_s2 take lists", k));
  if (!(a.tolerance_mm > 0)) throw InputError("--tolerance-mm must be positive (mm)");
  const std::string out = a.out_dir.empty() ? a.run.runs_root + "/overshoot-grid" : a.out_dir;
  g.out_dir = out;
  std::filesystem::create_directories(out);

  std::vector<std::string> shaper_opts;
  for (const auto& sh : a.shapers) {
    const auto eq = sh.find('=');
    if (eq == std::string::npos || (sh.substr(0, eq) != "x" && sh.substr(0, eq) != "y"))
      throw InputError(fmt::format("--shaper {}: expected AXIS=TYPE:FREQ_HZ[:DAMPING] with AXIS x or y", sh));
    shaper_opts.push_back("shaper_" + sh);
  }
  if (!shaper_opts.empty() && a.run.machine != "sim")
    throw InputError(
        "--shaper compares shaping on/off on the simulator; on a machine run the grid twice, with the "
        "firmware's input shaper enabled and disabled");
  // The shaped grid's simulator: the same with the shapers.
  std::shared_ptr<const protocols::MachineHost> shaped_host;
  if (!shaper_opts.empty()) {
    shaper_opts.insert(shaper_opts.begin(), a.sim_options.begin(), a.sim_options.end());
    shaped_host = simulated_machine(machine_run.profile, shaper_opts);
  }
  auto& cells = g.cells;
  const protocols::StopSignals stop_signals;  // between two grid points too (stop_signals.hpp)
  for (const bool shaped : shaper_opts.empty() ? std::vector<bool>{false} : std::vector<bool>{false, true})
    for (double v : lists["speed_mm_s"])
      for (double acc : lists["accel_mm_s2"]) {
        protocols::RunOptions o = machine_run;
        o.protocol = "axis-rectangle";
        if (shaped) o.host = shaped_host;
        for (const auto& [k, vals] : lists) o.params[k] = vals.front();
        o.params["speed_mm_s"] = v;
        o.params["accel_mm_s2"] = acc;
        o.run_dir = fmt::format("{}/v{:g}_a{:g}{}", out, v, acc, shaped ? "_shaped" : "");
        o.file_tag = "rect";
        if (progress) *progress << fmt::format("tunekit: grid point {:g} mm/s, {:g} mm/s^2\n", v, acc);
        const auto r = protocols::run_experiment(o);
        const auto an = overshoot_from_run_dir(r.run_dir, a.analysis, nullptr);
        double os = 0, st = 0;
        for (const auto& s : an.axes) {
          os = std::max(os, s.mean_overshoot_mm);
          st = std::max(st, s.mean_settling_time_s);
        }
        cells.push_back(
            {v, acc, os, st, an.motion_time_s, 0, std::filesystem::relative(r.run_dir, out).string(), shaped});
      }
  double mean_t = 0;
  for (const auto& c : cells) mean_t += c.completion_time_s;
  mean_t /= static_cast<double>(cells.size());
  g.mean_completion_time_s = mean_t;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    auto& c = cells[i];
    c.figure_of_merit = ident::overshoot_figure_of_merit(c.overshoot_mm, a.tolerance_mm, c.completion_time_s, mean_t);
    auto& b = c.input_shaping ? g.best_shaped : g.best;
    if (c.figure_of_merit > 0 && (!b || c.figure_of_merit > cells[*b].figure_of_merit)) b = i;
  }
  if (!g.best)
    outcome.warnings.push_back(fmt::format("no grid point keeps the overshoot within {:g} mm", a.tolerance_mm));
  if (!shaper_opts.empty() && !g.best_shaped)
    outcome.warnings.push_back(
        fmt::format("with input shaping no grid point keeps the overshoot within {:g} mm", a.tolerance_mm));
  return g;
}

nlohmann::json overshoot_grid_json(const OvershootGrid& g) {
  nlohmann::json grid = nlohmann::json::array();
  for (const auto& c : g.cells)
    grid.push_back({{"speed_mm_s", c.speed_mm_s},
                    {"accel_mm_s2", c.accel_mm_s2},
                    {"overshoot_mm", c.overshoot_mm},
                    {"settling_time_s", c.settling_time_s},
                    {"completion_time_s", c.completion_time_s},
                    {"figure_of_merit", c.figure_of_merit},
                    {"input_shaping", c.input_shaping},
                    {"run_dir", c.run_dir}});
  return grid;
}

nlohmann::json overshoot_best_json(const OvershootGridCell& c) {
  return {{"speed_mm_s", c.speed_mm_s},
          {"accel_mm_s2", c.accel_mm_s2},
          {"overshoot_mm", c.overshoot_mm},
          {"completion_time_s", c.completion_time_s},
          {"figure_of_merit", c.figure_of_merit}};
}

Envelope overshoot_grid_envelope(const OvershootOutcome& o) {
  const OvershootOptions& a = o.options;
  const OvershootGrid& g = *o.grid;
  Envelope env("overshoot");
  nlohmann::json lj = nlohmann::json::object();
  for (const auto& [k, v] : g.lists) lj[k] = v;
  env.set_options({{"grid", lj},
                   {"machine", a.run.machine},
                   {"sim", a.sim_options},
                   {"tolerance_mm", a.tolerance_mm},
                   {"band_mm", a.analysis.band_mm}});
  auto& res = env.results();
  res["grid"] = overshoot_grid_json(g);
  res["mean_completion_time_s"] = g.mean_completion_time_s;
  res["figure_of_merit"] =
      "normalized motion speed (mean completion time / completion time) where the overshoot "
      "is within the tolerance, else 0 (Hemminger, 2022)";
  if (g.best) {
    res["best"] = overshoot_best_json(g.cells[*g.best]);
    res["summary"] = nlohmann::json::array(
        {{{"label", "fastest speed within tolerance"}, {"path", "best.speed_mm_s"}, {"unit", "mm/s"}},
         {{"label", "its acceleration"}, {"path", "best.accel_mm_s2"}, {"unit", "mm/s^2"}},
         {{"label", "its overshoot"}, {"path", "best.overshoot_mm"}, {"unit", "mm"}},
         {{"label", "its completion time"}, {"path", "best.completion_time_s"}, {"unit", "s"}}});
  }
  if (!a.shapers.empty()) {
    res["input_shapers"] = a.shapers;
    if (g.best_shaped) res["best_shaped"] = overshoot_best_json(g.cells[*g.best_shaped]);
  }
  if (!g.report.empty()) res["report"] = g.report;
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

// The grid's report as a record: the fastest point within the tolerance (as results.json's summary
// lists it), the warnings and the grid's plot; `tunekit report` reads the same back from the files.
CalibrationRecord overshoot_grid_record(const OvershootOutcome& o) {
  const OvershootGrid& g = *o.grid;
  CalibrationRecord r;
  r.command = "overshoot";
  r.tool_version = core::kVersion;
  if (g.best) {
    const OvershootGridCell& c = g.cells[*g.best];
    r.summary = {{"fastest speed within tolerance", {c.speed_mm_s}, "mm/s", "n/a", "best.speed_mm_s", ""},
                 {"its acceleration", {c.accel_mm_s2}, "mm/s^2", "n/a", "best.accel_mm_s2", ""},
                 {"its overshoot", {c.overshoot_mm}, "mm", "n/a", "best.overshoot_mm", ""},
                 {"its completion time", {c.completion_time_s}, "s", "n/a", "best.completion_time_s", ""}};
  }
  r.warnings = o.warnings;
  OvershootGridPlot plot{o.options.tolerance_mm, {}};
  for (const auto& c : g.cells)
    plot.cells.push_back(
        {c.input_shaping, c.speed_mm_s, c.accel_mm_s2, c.overshoot_mm, c.completion_time_s, c.figure_of_merit});
  r.plots.overshoot_grid = plot;
  return r;
}

}  // namespace

OvershootOutcome compute_overshoot(const OvershootOptions& a, std::ostream* progress) {
  if (!(a.analysis.band_mm > 0)) throw InputError("--band-mm must be positive (mm)");
  if (!(a.analysis.tail_fraction > 0 && a.analysis.tail_fraction < 1))
    throw InputError("--tail must be between 0 and 1");
  if (a.input.empty() && a.params.empty() && a.shapers.empty())
    throw InputError(
        "give a run directory or CSV to analyze, or -p speed_mm_s=...,... / -p accel_mm_s2=...,... for a grid");
  OvershootOutcome outcome;
  outcome.options = a;
  if (!a.params.empty() || a.input.empty()) {
    if (!a.input.empty()) throw InputError("give either RUN (analyze) or -p lists (grid mode), not both");
    outcome.grid = compute_overshoot_grid(a, outcome, progress);
    // results.json is the envelope without the report's path; the report is rendered from the
    // grid's record, which `tunekit report` reads back from results.json and plotdata.json.
    const std::string out = outcome.grid->out_dir;
    const CalibrationRecord record = overshoot_grid_record(outcome);
    core::write_file_atomic(out + "/results.json", overshoot_grid_envelope(outcome).dump());
    core::write_file_atomic(out + "/plotdata.json", plotdata_json(record.plots).dump(2) + "\n");
    outcome.grid->report = render_report(out, record).html_path;
    return outcome;
  }
  outcome.analysis = std::filesystem::is_directory(a.input)
                         ? overshoot_from_run_dir(a.input, a.analysis, &outcome.inputs)
                         : overshoot_from_csv(a, outcome.inputs);
  outcome.warnings = outcome.analysis->warnings;
  return outcome;
}

Envelope to_envelope(const OvershootOutcome& o) {
  if (o.grid) return overshoot_grid_envelope(o);
  const OvershootOptions& a = o.options;
  Envelope env("overshoot");
  env.set_options({{"band_mm", a.analysis.band_mm},
                   {"tail_fraction", a.analysis.tail_fraction},
                   {"min_pause_s", a.analysis.min_pause_s},
                   {"min_move_mm", a.analysis.min_move_mm},
                   {"drift_order", a.analysis.drift_order}});
  for (const auto& in : o.inputs) add_input(env, in);
  if (o.analysis) env.results() = ident::to_json(*o.analysis, a.traces);
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

void print_text(const OvershootOutcome& o, std::ostream& os) {
  if (o.analysis) print_overshoot_analysis(os, *o.analysis);
  if (!o.grid) return;
  const OvershootGrid& g = *o.grid;
  os << fmt::format("overshoot grid ({} points), tolerance {:g} mm: {}\n", g.cells.size(), o.options.tolerance_mm,
                    g.out_dir);
  os << "  shaping speed_mm_s accel_mm_s2 overshoot_mm settle_s completion_s   FOM\n";
  for (std::size_t i = 0; i < g.cells.size(); ++i) {
    const auto& c = g.cells[i];
    os << fmt::format("  {:>7} {:>10g} {:>11g} {:>12.4f} {:>8.4f} {:>12.3f} {:>5.3f}{}\n",
                      c.input_shaping ? "on" : "off", c.speed_mm_s, c.accel_mm_s2, c.overshoot_mm, c.settling_time_s,
                      c.completion_time_s, c.figure_of_merit,
                      (g.best == i || g.best_shaped == i) ? "  <- fastest within tolerance" : "");
  }
  os << "report: " << g.report << "\n";
}

}  // namespace tunekit::calibration
