// tunekit calibrate, stage 2: the experiments run in the plan's order. The liquefier step test
// is identified as soon as it has run: its time constant sizes the chirp that follows.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "calibrate_stages.hpp"
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

ExperimentRuns run_experiments(const CalibrationPlan& plan, Progress& progress) {
  // A stop signal between two experiments stops the calibration too (stop_signals.hpp).
  const protocols::StopSignals stop_signals;
  ExperimentRuns out;
  out.chirp = plan.chirp;
  out.chirp_basis = plan.chirp_basis;
  for (const auto& e : plan.experiments) {
    double estimate_s = e.estimated_s;
    if (e.protocol == "liquefier-chirp" && out.liquefier_step && out.liquefier_step->analysis.pooled) {
      const double tau = out.liquefier_step->analysis.pooled->value("tau_s");
      if (std::isfinite(tau) && tau > 0) {
        const double sized = clamped_chirp_tau_s(tau);
        out.chirp = protocols::plan_liquefier_chirp(sized, e.checked.params.at("segment_s"));
        out.chirp_basis =
            fmt::format("the pooled step fit's time constant {} s (one tau over every step)", display_number(tau));
        if (sized != tau)
          out.chirp_basis += fmt::format(", held at {} s, the end of the range checked", display_number(sized));
        // The dry run timed the chirp of the plan; this one is longer or shorter by the difference.
        if (!e.params.count("duration_s"))
          estimate_s += designed_params(plan, e, out.chirp).params.at("duration_s") -
                        designed_params(plan, e, plan.chirp).params.at("duration_s");
      }
    }
    progress.begin("run " + e.name, plan.sim ? std::max(1.0, estimate_s / 4) : estimate_s);
    protocols::RunOptions run_options = experiment_run_options(plan, e, out.chirp, false);
    run_options.keep_heaters = plan.options.keep_heaters;
    // Predicted before it runs, from the experiment as it will run (the chirp sized again).
    const protocols::RunOptions dry = [&] {
      auto o = run_options;
      o.dry_run = true;
      return o;
    }();
    if (const auto predicted = predict_experiment(plan, protocols::run_experiment(dry).experiment,
                                                  measured_liquefier_prior(plan, out.liquefier_step)))
      out.predicted[e.name] = *predicted;
    const auto& run = out.runs[e.name] = protocols::run_experiment(run_options);
    progress.end(run.status);
    // The chirp as run: the protocol sized its staircase step from the chirp's end (never shorter
    // than the machine's), which sets the band the plan describes.
    if (e.protocol == "liquefier-chirp") {
      out.chirp = protocols::plan_liquefier_chirp(out.chirp.expected_tau_s, run.experiment.params.at("segment_s"));
      out.chirp.duration_s = run.experiment.params.at("duration_s");  // the design's (experiment_design.hpp)
    }
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
