// tunekit step: identify liquefier dynamics (K, tau, theta) from step-response logs
// (Holtrup 2019 ch. 4.4.2). Steps are found in the input column, or, for records without an input
// channel (ooze after a stop, Table B.1), given by --step-time and --step-size / --group.
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include <fmt/format.h>

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/step_command.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::cli {
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

}  // namespace

std::string step_model_option_name(fitting::StepModel model) {
  return model == fitting::StepModel::fo ? "fo" : "fopdt";
}
std::string step_instant_option_name(ident::StepInstant instant) {
  return instant == ident::StepInstant::first_sample ? "first" : "midpoint";
}

StepOutcome compute_step(const StepOptions& a) {
  StepOutcome outcome;
  outcome.options = a;
  if (!(a.analysis.detect.min_step_fraction > 0 && a.analysis.detect.min_step_fraction < 1))
    throw InputError("--min-step must be between 0 and 1 (a fraction of the input range)");
  const std::string bytes = ident::read_file_bytes(a.file);
  ident::CsvOptions copt;
  copt.columns = {a.output_column};
  if (!a.input_column.empty()) copt.columns.push_back(a.input_column);
  if (!a.group_column.empty()) copt.columns.push_back(a.group_column);
  copt.time_column = a.time_column;
  copt.find_time_column = a.time_column.empty();
  // With --group the time restarts in every group: check monotonic time per group below.
  copt.time_must_increase = a.group_column.empty();
  const auto table = ident::parse_csv(bytes, a.file, copt);
  const auto& tcol = table.column(table.time_column);
  const auto& ycol = table.column(a.output_column);
  if (table.rows < 10)
    throw InputError(fmt::format("too few samples ({}) for a step analysis; at least 10 are needed", table.rows),
                     a.file);

  ident::StepAnalysisOptions opt = a.analysis;
  opt.output_unit = unit_or_1(a.output_unit.empty() ? ycol.unit : a.output_unit);
  std::string input_unit = "1";
  if (!a.input_column.empty()) input_unit = unit_or_1(table.column(a.input_column).unit);
  else if (!a.group_column.empty()) input_unit = unit_or_1(table.column(a.group_column).unit);
  if (!a.input_unit.empty()) input_unit = a.input_unit;
  if (ident::is_volumetric_flow_unit(input_unit)) input_unit = "mm^3/s";
  opt.input_unit = input_unit;
  opt.gain_unit = opt.output_unit + "/(" + input_unit + ")";

  ident::StepAnalysis& res = outcome.analysis;
  try {
    if (!a.input_column.empty()) {
      if (!a.group_column.empty() || !std::isnan(a.step_size))
        throw InputError("--input finds the steps itself; do not combine it with --group or --step-size");
      res = ident::analyze_steps(tcol.values, table.column(a.input_column).values, ycol.values, opt);
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

  outcome.time_column = table.time_column;
  outcome.input_sha256 = sha256_hex(bytes);
  outcome.input_size_bytes = bytes.size();
  outcome.input_unit = input_unit;
  outcome.output_unit = opt.output_unit;
  outcome.gain_unit = opt.gain_unit;
  outcome.warnings = table.warnings;
  outcome.warnings.insert(outcome.warnings.end(), res.warnings.begin(), res.warnings.end());
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
       {"step_at", a.input_column.empty() ? nlohmann::json(nullptr)
                                          : nlohmann::json(step_instant_option_name(a.analysis.detect.instant))}});
  env.add_input_digest(a.file, o.input_sha256, o.input_size_bytes);
  env.results() = ident::to_json(o.analysis);
  env.results()["units"] = {{"input", o.input_unit}, {"output", o.output_unit}, {"K", o.gain_unit}, {"time", "s"}};
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
  os << fmt::format("  K in {}, y0 in {}; 95 % intervals in the JSON (--json)\n", o.gain_unit, o.output_unit);
}

namespace {
struct StepCommand {
  StepOptions options;
  OutputOptions output;
};

}  // namespace

void register_step(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<StepCommand>();
  StepOptions& o = cmd->options;
  auto* sub = app.add_subcommand("step", "Identify liquefier dynamics (K, tau, theta) from step-response logs");
  sub->add_option("file", o.file, "CSV log (time in s; units in column names, e.g. 'force (N)')")->required();
  sub->add_option("-t,--time", o.time_column,
                  "Time column (s; ms and us are converted); default: found by name (time, t, timestamp, time_s)");
  sub->add_option("-i,--input", o.input_column,
                  "Input column (e.g. feed rate, mm/s); its steps are found automatically");
  sub->add_option("-y,--output", o.output_column, "Output column (e.g. force in N, ooze length in mm)")->required();
  sub->add_option("--input-unit", o.input_unit,
                  "Unit of the input column when its name does not say it (e.g. mm3/s for a volumetric flow, mm/s "
                  "for filament feed); export places operating points by it");
  sub->add_option("--output-unit", o.output_unit, "Unit of the output column when its name does not say it");
  add_choice_option<fitting::StepModel>(
      sub, "-m,--model", o.analysis.model, {{"fo", fitting::StepModel::fo}, {"fopdt", fitting::StepModel::fopdt}},
      "fo: first order K/(tau s+1); fopdt: with dead time theta (s), needs samples before each step");
  sub->add_option("--group", o.group_column,
                  "Without --input: split the rows by this column's value (e.g. print speed, mm/s); each group is "
                  "one step of that size at --step-time, time restarting per group");
  sub->add_option("--step-time", o.step_time_s, "Without --input: when the step happened (s)")->capture_default_str();
  sub->add_option("--step-size", o.step_size,
                  "Without --input: the input change (input units, e.g. the print speed before a stop in mm/s)");
  sub->add_option("--min-step", o.analysis.detect.min_step_fraction,
                  "A change of the input larger than this fraction of its range (and than 8 times the input's own "
                  "noise) into a level the input holds is a step")
      ->capture_default_str();
  add_choice_option<ident::StepInstant>(
      sub, "--step-at", o.analysis.detect.instant,
      {{"midpoint", ident::StepInstant::midpoint}, {"first", ident::StepInstant::first_sample}},
      "With --input: when the input changed between the last sample at the old level and the first at "
      "the new one. midpoint: half-way (interpolated; for logs sampled independently of the changes, "
      "e.g. a printer's); first: at the first new sample (input changes exactly at sample instants). "
      "Moves t_step and theta_s (s) by up to half a sample interval");
  add_output_options(sub, cmd->output);
  sub->footer(
      "Model: y(t) = y0 + K du (1 - exp(-(t - t_step - theta)/tau)) after each step; each step is fitted on\n"
      "its own (start values by the log-incomplete-response method), then all steps pooled, then per operating\n"
      "point: the level each step arrives at (results 'operating_points', what export designs from): per level\n"
      "K, tau, theta with 95 % intervals, the counts of rising and falling arrivals and tau(rising) - tau(falling)\n"
      "with its interval; 'trend' fits tau_s = a u^b, K = a u^b and theta_s = c0 + c1 u over them (a flow sweep:\n"
      "tunekit run liquefier-flow-sweep). A pooled fit whose residuals are not white while its single-step fits'\n"
      "are is warned about: the steps do not share one K, tau, theta.\n"
      "Examples:\n"
      "  tunekit step datasets/liquefier/synthetic_steps.csv --time time --input feed --output force \\\n"
      "      --step-at first --json   # this data set's input changes exactly at sample instants\n"
      "  tunekit step runs/step-1/step.csv --input feed --output force   # a run of 'tunekit run liquefier-step'\n"
      "  tunekit step datasets/liquefier/holtrup_table_b1_ooze.csv --time t_s --output L_mm --group v_print_mm_s \\\n"
      "      --model fo          # Holtrup 2019 Table B.1: ooze length after a stop, one step per print speed\n"
      "  tunekit step ooze.csv --time t --output length --step-time 0 --step-size 20 --model fo\n"
      "  tunekit step log.csv --input flow_mm3_s --output force_N   # time_s found by name, units from the names\n"
      "Exit codes: 2 bad input (no step found, constant output, NaN, too few samples, time not increasing),\n"
      "1 the fit failed (no convergence, or tau not identifiable because the record is too short).");
  sub->callback([cmd, &ctx] { set_exit_code(report_outcome(compute_step(cmd->options), cmd->output, ctx)); });
}

}  // namespace tunekit::cli
