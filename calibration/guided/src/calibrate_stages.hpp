#pragma once
// Helpers shared by the stages of `tunekit calibrate` (calibration_pipeline.hpp).

#include <ostream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tunekit/calibration/guided/calibration_pipeline.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/protocols/experiment_design.hpp"

namespace tunekit::calibration {

/// Runs an analysis as a user's command would (the same compute function), keeping its message
/// and exit code but saying which analysis failed.
template <class Fn>
auto calibrate_analysis(const char* command, Fn&& compute) {
  try {
    return compute();
  } catch (const Error& e) {
    std::string msg = e.formatted();
    const std::string prefix = "tunekit: error: ";
    if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
    const std::string what = fmt::format("'tunekit {}' failed: {}", command, msg);
    if (e.code() == ExitCode::fit_failed) throw FitError(what);
    throw InputError(what);
  }
}

/// Writes an analysis' JSON envelope where the run keeps it (RUN_DIR/analysis/NAME.json, the
/// file the command's --json-file would write); returns the file as written, with its digest.
template <class Outcome>
InputFile keep_analysis(const Outcome& outcome, const std::string& json_path, CliContext& ctx) {
  if (ctx.verbosity > 0) print_text(outcome, ctx.err);
  std::string text = prepare_emission(to_envelope(outcome), OutputOptions{}).text;
  write_output_text(json_path, text);
  return InputFile::from_bytes(json_path, std::move(text));
}

/// The analysis' results as its JSON holds them (the same serialisation of the typed outcome).
template <class Outcome>
nlohmann::json analysis_results(const Outcome& outcome) {
  return to_envelope(outcome).results();
}

/// The run options of one planned experiment (`dry`: build and check only); a fine pass' band
/// from `fine_mode` (its coarse pass' mode; the plan's axis prior when null).
protocols::RunOptions experiment_run_options(const CalibrationPlan& plan, const PlannedExperiment& e,
                                             const protocols::ChirpPlan& chirp, bool dry,
                                             const protocols::AxisPrior* fine_mode = nullptr);

/// Builds and checks every planned experiment against the limits (the chirp for the extremes of
/// its time constants too), fills in their machine times and the chirp plan. InputError naming
/// the limit when one is exceeded.
void check_plan(CalibrationPlan& plan);

/// The intervals `built` (the plan's experiment `e`, as built) is expected to give with the
/// liquefier prior and the axis' mode given (the plan's priors, or what an earlier stage
/// measured); nullopt for an experiment no prediction is made for (a coarse pass).
std::optional<protocols::ExperimentPrediction> predict_experiment(const PlannedExperiment& e,
                                                                  const protocols::Experiment& built,
                                                                  const protocols::LiquefierPrior& liquefier,
                                                                  const protocols::AxisPrior& axis);

/// The parameters the experiment design gives `e` at the plan's scale (the chirp's for `chirp`'s
/// time constant, a fine pass' for `fine_mode`, the plan's axis prior when null); calibrate uses
/// them where --param did not set them.
protocols::DesignedParams designed_params(const CalibrationPlan& plan, const PlannedExperiment& e,
                                          const protocols::ChirpPlan& chirp,
                                          const protocols::AxisPrior* fine_mode = nullptr);

/// `given` with the plant's parameters of a whole-record model (`what` names it in the basis).
protocols::LiquefierPrior liquefier_prior_from(const protocols::LiquefierPrior& given, const ident::WholeRecordModel& m,
                                               const std::string& what);

/// The liquefier prior of the experiments after the step test: its whole-record model's
/// parameters when it has one, else the plan's.
protocols::LiquefierPrior measured_liquefier_prior(const CalibrationPlan& plan, const std::optional<StepOutcome>& step);

/// The path of `relative` (e.g. "machines/sim.toml") in the datasets bundled with tunekit's
/// sources (the folder is fixed when tunekit is built; "datasets" when it was not given).
std::string bundled_dataset_path(const std::string& relative);

/// The time constant (s) a chirp is sized from: `tau_s` within the range the plan checked.
double clamped_chirp_tau_s(double tau_s);

/// The liquefier step test analysed as `tunekit step FILE --input feed --output force` does.
StepOptions load_cell_step_options(const std::string& csv, const std::string& feed_track);

/// What the technician reads after the progress (calibrate_terminal.cpp): the record's summary
/// rows (each identified quantity, its value and 95 % interval or basis), the configuration's
/// settings (current, proposed, change), the diff, what to do next, and the report's path.
void print_calibrate_terminal(const CalibrationRecord& record, const CompensatorDesign& design,
                              const std::string& report, std::ostream& os);

/// Paths inside the run directory are written relative to it, so that results.json does not
/// depend on where the run lives (and two runs of one machine are byte-identical).
void strip_prefix(nlohmann::json& j, const std::string& prefix);

}  // namespace tunekit::calibration
