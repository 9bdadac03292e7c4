// tunekit step: identify liquefier dynamics (K, tau, theta) from step-response logs
// (Holtrup 2019 ch. 4.4.2). Steps are found in the input column, or, for records without an input
// channel (ooze after a stop, Table B.1), given by --step-time and --step-size / --group.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/calibrate_plotdata.hpp"

#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/analyses/whole_record.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/step_analysis.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {
namespace {

void print_fit_line(std::ostream& os, const std::string& label, const fitting::FitResult& f) {
  auto pm = [&](const char* n) {
    const auto& p = f.param(n);
    if (p.fixed) return fmt::format("{} = {:.4g} (fixed)", n, p.value);
    return fmt::format("{} = {:.4g} +- {:.2g}", n, p.value, p.std_error);
  };
  os << fmt::format("  {:<22} {}   {}   {}   rms {:.3g}  r2 {:.4f}\n", label, pm("K"), pm("tau_s"), pm("theta_s"),
                    f.diagnostics.rms, f.diagnostics.r2);
}

// --plot: the figure needs the input column, an .svg or .png name, and never the log's own path.
void check_plot_option(const StepOptions& a) {
  if (a.plot_out.empty()) return;
  if (a.input_column.empty()) throw InputError("--plot draws the record against its input: give --input COL");
  const auto ext = std::filesystem::path(a.plot_out).extension();
  if (ext != ".svg" && ext != ".png") throw InputError("--plot writes an .svg or .png file", a.plot_out);
  std::error_code ec;
  if (std::filesystem::equivalent(a.plot_out, a.file, ec))
    throw InputError("--plot names the log itself; give another file", a.plot_out);
}

// An axis label: the column and its unit ("feed (mm/s)"), the column alone when dimensionless.
std::string column_label(const std::string& column, const std::string& unit) {
  return unit == "1" ? column : fmt::format("{} ({})", column, unit);
}

}  // namespace

std::string step_model_option_name(fitting::StepModel model) {
  return model == fitting::StepModel::fo ? "fo" : "fopdt";
}
std::string step_instant_option_name(ident::StepInstant instant) {
  return instant == ident::StepInstant::first_sample ? "first" : "midpoint";
}

namespace {

// A warning that the steps' dynamics differ with the level is explained when the whole-record
// model (nonlinear: its tau follows the flow) describes the record to its noise: white residuals
// and no warning of its own (no step fit disagreeing with it).
bool explained_by_whole_record(const std::string& warning, const WholeRecordResult& wr) {
  if (warning.find(ident::kDoNotShareDynamics) == std::string::npos || !wr.model) return false;
  const auto& m = *wr.model;
  return !m.model.linear_chosen && m.warnings.empty() && m.model.fit.diagnostics.whiteness_p >= ident::kWhitenessAlarmP;
}

// The analysis options with the units of the log's columns (or the ones the options give).
ident::StepAnalysisOptions analysis_options(const StepOptions& a, const formats::CsvTable& table) {
  ident::StepAnalysisOptions opt = a.analysis;
  opt.output_unit = unit_or_1(a.output_unit.empty() ? table.column(a.output_column).unit : a.output_unit);
  std::string input_unit = "1";
  if (!a.input_column.empty()) input_unit = unit_or_1(table.column(a.input_column).unit);
  else if (!a.group_column.empty()) input_unit = unit_or_1(table.column(a.group_column).unit);
  if (!a.input_unit.empty()) input_unit = a.input_unit;
  if (formats::is_volumetric_flow_unit(input_unit)) input_unit = "mm^3/s";
  opt.input_unit = input_unit;
  opt.gain_unit = opt.output_unit == input_unit ? "1" : opt.output_unit + "/(" + input_unit + ")";
  return opt;
}

// The options checked before the log is read.
void check_step_options(const StepOptions& a) {
  if (!(a.analysis.detect.min_step_fraction > 0 && a.analysis.detect.min_step_fraction < 1))
    throw InputError("--min-step must be between 0 and 1 (a fraction of the input range)");
  check_plot_option(a);
}

}  // namespace

StepOutcome compute_step(const StepOptions& a) {
  check_step_options(a);
  const InputFile file = InputFile::read(a.file);
  std::optional<InputFile> track;
  if (!a.input_column.empty())
    if (const std::string path = feed_track_for(a.feed_track, a.file); !path.empty()) track = InputFile::read(path);
  return compute_step(a, file, track ? &*track : nullptr);
}

StepOutcome compute_step(const StepOptions& a, const InputFile& file, const InputFile* feed_track) {
  StepOutcome outcome;
  outcome.options = a;
  check_step_options(a);
  const std::string_view bytes = file.bytes();
  formats::CsvOptions copt;
  copt.columns = {a.output_column};
  if (!a.input_column.empty()) copt.columns.push_back(a.input_column);
  if (!a.group_column.empty()) copt.columns.push_back(a.group_column);
  copt.time_column = a.time_column;
  copt.find_time_column = a.time_column.empty();
  // With --group the time restarts in every group: check monotonic time per group below.
  copt.time_must_increase = a.group_column.empty();
  const auto table = formats::parse_csv(bytes, a.file, copt);
  const auto& tcol = table.column(table.time_column);
  const auto& ycol = table.column(a.output_column);
  if (table.rows < 10)
    throw InputError(fmt::format("too few samples ({}) for a step analysis; at least 10 are needed", table.rows),
                     a.file);

  const ident::StepAnalysisOptions opt = analysis_options(a, table);
  const std::string& input_unit = opt.input_unit;

  ident::StepAnalysis& res = outcome.analysis;
  // The feed track on the record's clock: the step fits and the whole-record model follow it
  // where it matches the logged feed (a stop between moves lies where the planner put it).
  std::optional<ident::FeedTrackAlignment> track;
  if (!a.input_column.empty()) track = aligned_feed_track(feed_track, tcol.values, table.column(a.input_column).values);
  const ident::FeedTrack* steps_track = track && track->matches ? &track->aligned : nullptr;
  try {
    if (!a.input_column.empty()) {
      if (!a.group_column.empty() || !std::isnan(a.step_size))
        throw InputError("--input finds the steps itself; do not combine it with --group or --step-size");
      res = ident::analyze_steps(tcol.values, table.column(a.input_column).values, ycol.values, opt, steps_track);
    } else {
      std::map<double, std::vector<std::size_t>> groups;
      if (!a.group_column.empty()) {
        const auto& g = table.column(a.group_column).values;
        for (std::size_t i = 0; i < g.size(); ++i) groups[g[i]].push_back(i);
      } else {
        if (std::isnan(a.step_size))
          throw InputError("without --input give the step: --step-size DU (and --step-time T), or --group COL");
        for (std::size_t i = 0; i < table.rows; ++i) groups[0].push_back(i);
      }
      std::vector<ident::KnownStep> ks;
      // Descending by the group value (the order of Holtrup's (2019) tables: 50, 20, 12.2, 2 mm/s).
      for (auto it = groups.rbegin(); it != groups.rend(); ++it) {
        ident::KnownStep k;
        const double du = std::isnan(a.step_size) ? it->first : a.step_size;
        k.u_before = 0;
        k.u_after = du;
        k.record.t_step = a.step_time_s;
        k.record.du = du;
        for (std::size_t i : it->second) {
          if (!k.record.t.empty() && !(tcol.values[i] > k.record.t.back()))
            throw InputError(
                fmt::format("time is not increasing ({} s after {} s){}", tcol.values[i], k.record.t.back(),
                            a.group_column.empty() ? std::string()
                                                   : fmt::format(" in group {} = {:g}", a.group_column, it->first)),
                source_location(a.file, table.header_line + i + 1));
          k.record.t.push_back(tcol.values[i]);
          k.record.y.push_back(ycol.values[i]);
        }
        ks.push_back(std::move(k));
      }
      res = ident::analyze_known_steps(ks, opt);
    }
  } catch (const Error& e) {
    if (!e.location().empty()) throw;
    if (e.code() == ExitCode::bad_input) throw InputError(e.message(), a.file);
    if (e.code() == ExitCode::fit_failed) throw FitError(e.message(), a.file);
    throw;
  }

  if (!a.input_column.empty()) {  // the whole-record model beside the per-step fits: any excitation
    const auto& u = table.column(a.input_column).values;
    if (feed_track) outcome.feed_track_input = feed_track->digest();
    outcome.record = {tcol.values, u, ycol.values};
    outcome.whole_record = ident::fit_whole_record(tcol.values, u, ycol.values, input_unit, opt.output_unit, &res,
                                                   a.profile_intervals, res.warnings, track ? &*track : nullptr);
  }
  outcome.time_column = table.time_column;
  outcome.input_sha256 = file.digest().sha256;
  outcome.input_size_bytes = bytes.size();
  outcome.input_unit = input_unit;
  outcome.output_unit = opt.output_unit;
  outcome.gain_unit = opt.gain_unit;
  outcome.warnings = table.warnings;
  for (auto& w : res.warnings)
    (explained_by_whole_record(w, outcome.whole_record) ? outcome.notes : outcome.warnings).push_back(std::move(w));
  if (!a.plot_out.empty())
    render_figure(step_figure(step_plotdata(outcome, column_label(a.input_column, outcome.input_unit),
                                            column_label(a.output_column, outcome.output_unit))),
                  a.plot_out);
  return outcome;
}

Envelope to_envelope(const StepOutcome& o) {
  const StepOptions& a = o.options;
  Envelope env("step");
  env.set_options(
      {{"time_column", o.time_column},
       {"input_column", a.input_column},
       {"input_unit", a.input_unit},
       {"output_unit", a.output_unit},
       {"output_column", a.output_column},
       {"model", step_model_option_name(a.analysis.model)},
       {"group_column", a.group_column},
       {"step_time_s", a.step_time_s},
       {"step_size", std::isnan(a.step_size) ? nlohmann::json(nullptr) : nlohmann::json(a.step_size)},
       {"min_step_fraction", a.analysis.detect.min_step_fraction},
       {"profile_intervals", a.profile_intervals},
       {"step_at", a.input_column.empty() ? nlohmann::json(nullptr)
                                          : nlohmann::json(step_instant_option_name(a.analysis.detect.instant))}});
  env.add_input_digest(a.file, o.input_sha256, o.input_size_bytes);
  env.results() = ident::to_json(o.analysis);
  env.results()["units"] = {{"input", o.input_unit}, {"output", o.output_unit}, {"K", o.gain_unit}, {"time", "s"}};
  add_whole_record(env, o.whole_record);
  env.results()["notes"] = o.notes;
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

void print_text(const StepOutcome& o, std::ostream& os) {
  const ident::StepAnalysis& res = o.analysis;
  os << fmt::format("{}: {} step(s), model {}\n", o.options.file, res.steps.size(),
                    fitting::model_name(o.options.analysis.model));
  for (const auto& s : res.steps) {
    const std::string label =
        fmt::format("step {} {} @{:.4g}s", s.step.index, s.step.rising() ? "up" : "down", s.step.t_step_s);
    if (s.fit) print_fit_line(os, label, *s.fit);
    else os << fmt::format("  {:<22} failed: {}\n", label, s.error);
  }
  if (res.pooled) print_fit_line(os, "pooled", *res.pooled);
  os << "  operating points (the level each step arrives at):\n";
  for (const auto& l : res.arrival_levels)
    print_fit_line(os, fmt::format("u = {:.4g} ({} step{})", l.u, l.steps.size(), l.steps.size() == 1 ? "" : "s"),
                   l.fit);
  bool both = false;
  for (const auto& l : res.arrival_levels) both = both || (l.n_rising > 0 && l.n_falling > 0);
  if (both) {
    os << "  rising/falling arrivals, tau rising - falling with its 95 % interval:\n";
    for (const auto& l : res.arrival_levels) {
      std::string rmf = "-";
      if (std::isfinite(l.rmf_ci95_lo))
        rmf = fmt::format("{:+.3g} s [{:+.3g}, {:+.3g}]{}", l.rising_minus_falling_tau_s, l.rmf_ci95_lo, l.rmf_ci95_hi,
                          l.directions_differ() ? " differ" : "");
      os << fmt::format("    u = {:<8.4g} {}/{}  {}\n", l.u, l.n_rising, l.n_falling, rmf);
    }
  }
  const auto& tr = res.level_trends;
  if (tr.tau) {
    const auto& b = tr.tau->param("b");
    os << fmt::format("  trend: tau_s = {:.4g} * u^{:.3g} (b 95 %: [{:.3g}, {:.3g}])", tr.tau->value("a"), b.value,
                      b.ci95_lo, b.ci95_hi);
    if (tr.K) os << fmt::format("   K = {:.4g} * u^{:.3g}", tr.K->value("a"), tr.K->value("b"));
    os << "\n";
  }
  print_whole_record(os, o.whole_record);
  for (const auto& n : o.notes) os << "  note (explained by the whole-record model): " << n << "\n";
  os << fmt::format("  K in {}, y0 in {}; 95 % intervals in the JSON (--json)\n", o.gain_unit, o.output_unit);
}

}  // namespace tunekit::calibration
