// tunekit calibrate: the technician's one command. It checks every experiment against the
// machine profile before anything is sent, runs them (liquefier flow sweep: feed steps up and
// down through flow levels of the hot end's range; liquefier chirp;
// axis sweeps of X and Y), identifies the models with the functions behind the commands a user
// would run by hand (compute_step, compute_freq, compute_shaper on the CSV files the run wrote;
// their typed outcomes), designs pressure advance and input shaping (compute_export), previews
// the firmware configuration change, and writes a run directory:
//   RUN_DIR/results.json     the envelope: every identified value, compensators, summary, and
//                            for each analysis the command that reproduces it (reproduce)
//   RUN_DIR/plotdata.json    the series behind the report's plots
//   RUN_DIR/report.html      one self-contained page (rebuild with `tunekit report RUN_DIR`)
//   RUN_DIR/<experiment>/    each experiment's journal, raw CSV data and (sim) truth.json
//   RUN_DIR/analysis/*.json  each analysis command's own JSON; analysis/README names the commands
//   RUN_DIR/config/          the configuration before and after, and the diff
// The stages are in calibration_pipeline.hpp, one source file each (calibrate_plan.cpp,
// calibrate_run.cpp, calibrate_identify.cpp, calibrate_design.cpp, calibrate_results.cpp).
#include <algorithm>
#include <unistd.h>

#include "calibrate_stages.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/protocols/stop_signals.hpp"

namespace tunekit::calibration {

void strip_prefix(nlohmann::json& j, const std::string& prefix) {
  if (j.is_string()) {
    std::string s = j.get<std::string>();
    for (std::size_t pos; (pos = s.find(prefix)) != std::string::npos;) s.erase(pos, prefix.size());
    j = s;
  } else if (j.is_structured()) {
    for (auto& v : j) strip_prefix(v, prefix);
  }
}

namespace {

/// "tau_ref_s +-0.61 %, b +-0.0066" (a relative half-width, or an absolute one for a quantity
/// near 0), each with the unbudgeted design's in brackets when there is one.
std::string prediction_text(const protocols::ExperimentPrediction& p,
                            const std::optional<protocols::ExperimentPrediction>& unbudgeted) {
  const auto one = [](const protocols::PredictedInterval& i) {
    return i.quantity == "b" ? fmt::format("+-{:.2g}", i.half_width) : fmt::format("+-{:.2g} %", 100 * i.relative());
  };
  std::string text;
  for (const auto& i : p.intervals) {
    text += fmt::format("{}{} {}", text.empty() ? "" : ", ", i.quantity, one(i));
    if (const auto* u = unbudgeted ? unbudgeted->find(i.quantity) : nullptr) text += fmt::format(" [{}]", one(*u));
  }
  return text;
}

/// calibrate --dry-run: the plan as checked (each experiment's protocol, parameters with the
/// reasons of those derived from the machine, and machine time), as JSON or text.
int print_plan(const CalibrationPlan& plan, CliContext& ctx) {
  Envelope env("calibrate");
  nlohmann::json exps = nlohmann::json::array();
  double total_s = 0;
  for (const auto& e : plan.experiments) {
    nlohmann::json j = e.checked.to_json();
    j["name"] = e.name;
    if (e.predicted) j["predicted"] = e.predicted->to_json();
    if (e.unbudgeted) j["predicted_without_budget"] = e.unbudgeted->to_json();
    exps.push_back(j);
    total_s += e.estimated_s;
  }
  env.results() = {{"dry_run", true},
                   {"profile", plan.profile.profile.name},
                   {"profile_source", plan.profile.path},
                   {"firmware", plan.options.firmware},
                   {"experiments", exps},
                   {"machine_time_s", total_s},
                   {"design_scale", plan.design_scale}};
  if (plan.output.json || !plan.output.output_path.empty()) return emit(env, plan.output, ctx);
  ctx.out << fmt::format("calibrate plan for {} ({}), checked against its limits; nothing was sent\n",
                         plan.profile.profile.name, plan.options.firmware);
  for (const auto& e : plan.experiments) {
    ctx.out << fmt::format("  {:<16} {:<22} ~{:.1f} s of machine time\n", e.name, e.protocol, e.estimated_s);
    if (const auto it = e.checked.excitation.find("machine_defaults"); it != e.checked.excitation.end())
      for (const auto& [name, why] : it->items())
        ctx.out << fmt::format("      {} = {:g}: {}\n", name, e.checked.params.at(name), why.get<std::string>());
    if (const auto design = designed_params(plan, e, plan.chirp); !design.why.empty())
      ctx.out << fmt::format("      design: {}\n", design.why);
    if (e.predicted)
      ctx.out << fmt::format("      predicted 95 % intervals: {}\n", prediction_text(*e.predicted, e.unbudgeted));
  }
  if (std::any_of(plan.experiments.begin(), plan.experiments.end(), [](const auto& e) { return e.predicted; }))
    ctx.out << "  the predicted intervals are the sensors' noise alone (each fit's Cramer-Rao bound for a model\n"
               "  that describes the machine exactly); a real machine's departures from the models (more modes,\n"
               "  friction, a sensor's drift) widen what its fits report\n";
  if (plan.options.budget_s > 0)
    ctx.out << fmt::format("  budget {:g} s: {}\n", plan.options.budget_s,
                           plan.design_scale < 1 ? fmt::format("the sweeps, holds and chirp at {:.2f} of the design's "
                                                               "time (each interval's width without the budget in [])",
                                                               plan.design_scale)
                                                 : std::string("the design fits it"));
  ctx.out << fmt::format("  total ~{:.1f} s of machine time ('tunekit run PROTOCOL --dry-run' prints its G-code)\n",
                         total_s);
  return 0;
}

/// The experiment that ran last (the plan's order).
const protocols::RunResult& last_run(const CalibrationPlan& plan, const ExperimentRuns& runs) {
  for (auto e = plan.experiments.rbegin(); e != plan.experiments.rend(); ++e)
    if (const auto it = runs.runs.find(e->name); it != runs.runs.end()) return it->second;
  return runs.runs.begin()->second;
}

}  // namespace

int run_calibrate(const CalibrateArgs& given, CliContext& ctx, Progress& progress) {
  // `--machine DEVICE --profile FILE`: the machine named by its device is the port to use.
  CalibrateArgs options = given;
  if (options.machine != "sim" && options.port.empty()) options.port = options.machine;
  const CalibrationProfile profile = load_calibration_profile(options);
  const bool can_prompt = ::isatty(STDIN_FILENO) != 0 && ctx.interactive;
  const CalibrationPlan plan = plan_calibration(options, profile, can_prompt);
  if (plan.options.dry_run) return print_plan(plan, ctx);
  progress.expect(static_cast<int>(plan.experiments.size()) + 3);
  // A stop signal at any instant, the analysis and the report included, ends the calibration
  // with exit code 128 + its number; the last experiment's run.json says where (stop_signals.hpp).
  const protocols::StopSignals stop_signals;
  const ExperimentRuns runs = run_experiments(plan, progress);
  const auto stop_point = [&](const std::string& where) {
    if (!runs.runs.empty()) protocols::throw_if_stopped_after_run(last_run(plan, runs), "calibrate: " + where);
    protocols::StopSignals::throw_if_stopped("calibrate: " + where);
  };
  stop_point("after the experiments, before identifying the models");
  const Identification identified = identify(plan, runs, progress, ctx);
  stop_point("after the experiments, while identifying the models");
  const CompensatorDesign design = design_and_export(plan, runs, identified, progress, ctx);
  stop_point("after the experiments, while designing the compensators");
  const int code = write_run(plan, runs, identified, design, progress, ctx);
  stop_point("after the experiments, while writing the results and the report");
  return code;
}

}  // namespace tunekit::calibration
