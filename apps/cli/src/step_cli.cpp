// tunekit step: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/step_analysis.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <map>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct StepCommand {
  StepOptions options;
  OutputOptions output;
};

}  // namespace

CLI::App* add_step_command(CLI::App& app, StepOptions& o, OutputOptions& output) {
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
  sub->add_flag("--profile-intervals", o.profile_intervals,
                "With --input: the whole-record model's 95 % intervals of b and theta_s by profile likelihood "
                "(several times slower; default: Wald intervals widened for correlated residuals)");
  add_feed_track_option(sub, o.feed_track);
  sub->add_option("--plot", o.plot_out,
                  "With --input: also draw the record, the whole-record model, each step's fit and the residuals "
                  "(the calibration report's step figure) into this .svg or .png file");
  add_output_options(sub, output);
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
  return sub;
}

void register_step(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<StepCommand>();
  add_step_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_step(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
