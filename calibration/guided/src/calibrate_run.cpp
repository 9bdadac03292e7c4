// tunekit calibrate, stage 2: the experiments run in the plan's order. The liquefier step test
// is identified as soon as it has run: its time constant sizes the chirp that follows.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "calibrate_stages.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/core/input_read_scope.hpp"
#include "tunekit/ident/commanded_motion.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/stop_signals.hpp"

namespace tunekit::calibration {

StepOptions load_cell_step_options(const std::string& csv, const std::string& feed_track) {
  // The analysis `tunekit step` makes of this log with its defaults: the same steps and
  // operating points (the levels the steps arrive at), which export designs from.
  StepOptions so;
  so.file = csv;
  so.feed_track = feed_track;
  so.time_column = "time";
  so.input_column = "feed";
  so.output_column = "force";
  return so;
}

protocols::LiquefierPrior liquefier_prior_from(const protocols::LiquefierPrior& given, const ident::WholeRecordModel& m,
                                               const std::string& what) {
  protocols::LiquefierPrior prior = given;
  const auto& f = m.model.fit;
  prior.tau_ref_s = f.value("tau_ref_s");
  prior.ref_feed_mm_s = m.model.reference_input;
  prior.b = f.value("b");
  prior.theta_s = f.value("theta_s");
  if (m.model.sensor == fitting::LiquefierSensor::flow) prior.gain_N_per_mm_s = f.value("g");
  prior.basis =
      fmt::format("{} (tau {} s at {} mm/s, b {}, theta {} s)", what, display_number(prior.tau_ref_s),
                  display_number(prior.ref_feed_mm_s), display_number(prior.b), display_number(prior.theta_s));
  return prior;
}

protocols::LiquefierPrior measured_liquefier_prior(const CalibrationPlan& plan,
                                                   const std::optional<StepOutcome>& step) {
  if (!step || !step->whole_record.model) return plan.liquefier_prior;
  return liquefier_prior_from(plan.liquefier_prior, *step->whole_record.model, "the flow sweep's whole-record model");
}

namespace {

/// The chirp sized again from the step test's pooled time constant (clamped to the range the plan
/// checked), when it has one.
void resize_chirp(const PlannedExperiment& e, ExperimentRuns& out) {
  if (!out.liquefier_step || !out.liquefier_step->analysis.pooled) return;
  const double tau = out.liquefier_step->analysis.pooled->value("tau_s");
  if (!(std::isfinite(tau) && tau > 0)) return;
  const double sized = clamped_chirp_tau_s(tau);
  out.chirp = protocols::plan_liquefier_chirp(sized, e.checked.params.at("segment_s"));
  out.chirp_basis =
      fmt::format("the pooled step fit's time constant {} s (one tau over every step)", display_number(tau));
  if (sized != tau)
    out.chirp_basis += fmt::format(", held at {} s, the end of the range checked", display_number(sized));
}

/// The mode the coarse pass `coarse` located: the dominant mode of its record analysed as
/// `tunekit resonance` analyses it, the prior of its fine pass; the plan's axis prior, saying
/// why, when it located none.
protocols::AxisPrior located_mode(const CalibrationPlan& plan, const PlannedExperiment& coarse,
                                  const protocols::RunResult& run, std::map<std::string, std::string>& kept) {
  protocols::AxisPrior mode = plan.axis_prior;
  AccelFilesOptions o;
  o.files = {run.files.at(protocols::RunFile::accel)};
  // Read once: the record and its motion kept for the axis' analysis after the runs.
  const core::InputReadScope read_once;
  for (const auto& path : {o.files.front(), ident::commanded_motion_beside(o.files.front())})
    if (!path.empty()) kept[path] = read_file_bytes(path);
  o.input.axis = coarse.axis.empty() ? 0 : coarse.axis[0];
  o.digest_inputs = false;
  try {
    for (const auto& axis : analyze_accel_files(o).axes) {
      const auto& modes = axis.modes.modes;
      if (modes.empty()) continue;
      const auto& m = modes[axis.modes.dominant >= 0 ? static_cast<std::size_t>(axis.modes.dominant) : 0];
      if (!(m.freq_hz > 0 && m.zeta > 0)) continue;
      mode.freq_hz = m.freq_hz;
      mode.zeta = m.zeta;
      mode.basis =
          fmt::format("{}'s mode ({} Hz, damping ratio {}), accelerometer {:g} mm/s^2 rms at {:g} Hz", coarse.name,
                      display_number(m.freq_hz), display_number(m.zeta), mode.noise_mm_s2, mode.rate_hz);
      return mode;
    }
    mode.basis += fmt::format("; {} located no mode", coarse.name);
  } catch (const Error& e) {
    mode.basis += fmt::format("; {} located no mode: {}", coarse.name, e.message());
  }
  return mode;
}

}  // namespace

ExperimentRuns run_experiments(const CalibrationPlan& plan, Progress& progress) {
  // A stop signal between two experiments stops the calibration too (stop_signals.hpp).
  const protocols::StopSignals stop_signals;
  ExperimentRuns out;
  out.chirp = plan.chirp;
  out.chirp_basis = plan.chirp_basis;
  for (const auto& e : plan.experiments) {
    if (e.protocol == "liquefier-chirp") resize_chirp(e, out);
    const auto fine = out.fine_modes.find(e.name);
    const protocols::AxisPrior* fine_mode = fine != out.fine_modes.end() ? &fine->second : nullptr;
    protocols::RunOptions run_options = experiment_run_options(plan, e, out.chirp, false, fine_mode);
    run_options.keep_heaters = plan.options.keep_heaters;
    // Built and predicted before it runs, as it will run (the chirp sized again, a fine pass'
    // band from its coarse pass' mode, inside the envelope the plan checked).
    const protocols::Experiment planned = [&] {
      auto o = run_options;
      o.dry_run = true;
      return protocols::run_experiment(o).experiment;
    }();
    const double estimate_s = planned.estimated_duration_s;
    progress.begin("run " + e.name, plan.sim ? std::max(1.0, estimate_s / 4) : estimate_s);
    if (const auto predicted = predict_experiment(e, planned, measured_liquefier_prior(plan, out.liquefier_step),
                                                  fine_mode ? *fine_mode : plan.axis_prior))
      out.predicted[e.name] = *predicted;
    const auto& run = out.runs[e.name] = protocols::run_experiment(run_options);
    progress.end(run.status);
    // The chirp as run: the protocol sized its staircase step from the chirp's end (never shorter
    // than the machine's), which sets the band the plan describes.
    if (e.protocol == "liquefier-chirp") {
      out.chirp = protocols::plan_liquefier_chirp(out.chirp.expected_tau_s, run.experiment.params.at("segment_s"));
      out.chirp.duration_s = run.experiment.params.at("duration_s");  // the design's (experiment_design.hpp)
    }
    if (!e.locates.empty() && run.files.count(protocols::RunFile::accel))
      out.fine_modes[e.locates] = located_mode(plan, e, run, out.coarse_bytes);
    if (e.name == "liquefier-step") {
      const auto track = run.files.find(protocols::RunFile::feed_track);
      const auto options = load_cell_step_options(run.files.at(protocols::RunFile::load_cell),
                                                  track != run.files.end() ? track->second : std::string());
      out.liquefier_step = calibrate_analysis("step", [&] { return compute_step(options); });
    }
    protocols::throw_if_stopped_after_run(run, "after the experiment " + e.name + " had ended, before the next stage");
  }
  return out;
}

}  // namespace tunekit::calibration
