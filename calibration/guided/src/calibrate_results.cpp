// tunekit calibrate, stage 5: the run's record. results.json is built from the stages' typed
// outcomes (each analysis' results as its own JSON holds them, the summary rows, notes and the
// agreement of the two liquefier time constants), then plotdata.json, report.html, the
// analysis README and, with --record, the history.
#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "calibrate_liquefier.hpp"
#include "tunekit/calibration/analyses/calibrate_plotdata.hpp"
#include "calibrate_stages.hpp"
#include "tunekit/calibration/presentation/report_command.hpp"
#include "tunekit/fitting/stats.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/calibration/analyses/agreement.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

/// Two-sided 95 % quantile of the normal distribution: the advance's interval from its standard error.

// What results.json and plotdata.json are assembled in.
struct RunRecord {
  Envelope env{"calibrate"};
  nlohmann::json plot = nlohmann::json::object();
  nlohmann::json summary = nlohmann::json::array();
  nlohmann::json agreement = nlohmann::json::array();
  nlohmann::json notes = nlohmann::json::array();
  nlohmann::json& res() { return env.results(); }
  // A summary row: the value at `path`, its 95 % interval at `ci_path` or, without one, its basis.
  void row(const std::string& label, const std::string& path, const std::string& unit, const std::string& ci_path,
           const std::string& basis = "") {
    nlohmann::json r{{"label", label}, {"path", path}, {"unit", unit}};
    if (!ci_path.empty()) r["ci_path"] = ci_path;
    else r["basis"] = basis;
    summary.push_back(r);
  }
};

// An estimate for the agreement check from a fitted parameter with its 95 % interval; false when
// it has none or it is not finite.
bool calibrate_estimate(const fitting::Param& p, const std::string& method, Estimate& out) {
  out = {method, p.value, p.ci95_lo, p.ci95_hi};
  return std::isfinite(out.value) && std::isfinite(out.ci95_lo) && std::isfinite(out.ci95_hi);
}

// The liquefier as the whole-record model identifies it from the flow sweep (one model for every
// step: tau = a u^b, a dead time and the load cell's gain): its time constant at the model's
// reference feed (the median feed, where its interval is narrowest) in that feed's flow, its flow
// exponent, the dead time and the gain. The pooled step fit, one tau for steps at flows whose
// time constants differ, stays in the results for information.
// `where`: the reference input in words ("3.6 mm^3/s"); `model`: the model's name in the rows;
// `gain`: the gain's name when the model's sensor reads the flow.
struct WholeRecordWords {
  std::string where, model = "whole-record model", gain = "liquefier gain K";
};

void add_whole_record_rows(RunRecord& r, const ident::WholeRecordModel& m, const WholeRecordWords& w) {
  const std::string p = "liquefier.step.whole_record.";
  r.row(fmt::format("liquefier time constant tau at {} ({})", w.where, w.model), p + "tau_ref_s.value", "s",
        p + "tau_ref_s.ci95");
  if (!m.model.fit.param("b").fixed)
    r.row(fmt::format("tau's flow exponent b (tau = a u^b, {})", w.model), p + "b.value", "1", p + "b.ci95");
  r.row(fmt::format("liquefier dead time theta ({})", w.model), p + "theta_s.value", "s", p + "theta_s.ci95");
  const bool flow_sensor = m.model.sensor == fitting::LiquefierSensor::flow;
  r.row(fmt::format("{} ({})", flow_sensor ? w.gain : "force per stored filament g", w.model),
        p + "model.params.g.value", m.model.fit.param("g").unit, p + "model.params.g.ci95");
}

// The camera path's two dead times: the line test's (its whole-record model's, else its pooled
// fit's) and the one the ring's phase implies with the lines' tau, which does not depend on where
// the photo places the lines on their paths (docs/calibrate.md). They differ when that placement is
// off, or the ring's start direction.
void add_camera_theta_agreement(RunRecord& r, const CameraAnalysis& cam, const StepOutcome& widths) {
  if (!cam.ring_predicted || !cam.results.contains("ring")) return;
  const auto& ring = cam.results.at("ring");
  const auto ci = ring.value("theta_from_phase_ci95_s", nlohmann::json());
  if (!ci.is_array() || ci.size() != 2 || !ci[0].is_number() || !ci[1].is_number()) return;
  const Estimate by_ring{"ring test's phase", ring.at("theta_from_phase_s").get<double>(), ci[0].get<double>(),
                         ci[1].get<double>()};
  const fitting::FitResult* lines_fit = widths.whole_record.model ? &widths.whole_record.model->model.fit
                                        : widths.analysis.pooled  ? &*widths.analysis.pooled
                                                                  : nullptr;
  Estimate by_lines;
  if (lines_fit == nullptr || !calibrate_estimate(lines_fit->param("theta_s"), "line test", by_lines)) return;
  auto a =
      compare_estimates("liquefier dead time theta", "s", by_lines, by_ring, fitting::equivalence_margin("theta_s"));
  a["id"] = "theta";
  if (!a.at("agree").get<bool>()) r.env.warn(a.at("statement").get<std::string>());
  r.agreement.push_back(a);
}

void add_camera(RunRecord& r, const CameraAnalysis& cam, const StepOutcome& widths, double filament_area_mm2) {
  r.res()["liquefier"]["step"] = analysis_results(widths);
  r.res()["liquefier"]["camera"] = cam.results;
  r.plot["step"] = step_plotdata(widths, "feed (mm/s)", "delivered feed (mm/s, from the width)");
  r.plot["linewidth"] = cam.linewidth_plot;
  // The whole-record model of the line widths, as the load-cell path lists it; the pooled fit of
  // the line test's two levels when the model could not be fitted. Each width sample's set-point
  // is the commanded width's mean over the sample's window (vision::map_path), which places the
  // line test's flow changes inside their samples: over 40 simulated seeds the model's dead time
  // then covered the truth 97.5 % of the time, its tau 92.5 % (31 and 71.5 % over 200 seeds with
  // the set-point taken at each sample's centre; docs/interval-coverage.md).
  if (const auto& m = widths.whole_record.model) {
    add_whole_record_rows(
        r, *m, {display_number(m->model.reference_input * filament_area_mm2) + " mm^3/s", "line widths", "width gain"});
  } else {
    const std::string p = "liquefier.step.pooled.params.";
    r.row("liquefier time constant tau (line widths)", p + "tau_s.value", "s", p + "tau_s.ci95");
    r.row("liquefier dead time theta (line widths)", p + "theta_s.value", "s", p + "theta_s.ci95");
    r.row("width gain K (line widths)", p + "K.value", "1", p + "K.ci95");
  }
  if (cam.ring) {
    const std::string p = "liquefier.camera.ring.";
    r.row("ring frequency", p + "freq_hz", "Hz", "", "set by the test (N v / (2 pi R))");
    r.row("ring gain (measured)", p + "gain", "1", p + "gain_ci95");
    r.row("ring phase (measured)", p + "phase_deg", "deg", p + "phase_ci95_deg");
    if (cam.ring_predicted) {
      r.row("ring phase (step model)", p + "model_phase_deg", "deg", p + "model_phase_ci95_deg");
      r.row("dead time from the ring's phase", p + "theta_from_phase_s", "s", p + "theta_from_phase_ci95_s");
    }
  }
  add_camera_theta_agreement(r, cam, widths);
  for (const auto& w : cam.warnings) r.env.warn(w);
}

void add_load_cell_step(RunRecord& r, const StepOutcome& step, double filament_area_mm2) {
  auto& j = r.res()["liquefier"]["step"] = analysis_results(step);
  r.plot["step"] = step_plotdata(step, "feed (mm/s)", "force (N)");
  std::string levels;
  const auto& arrivals = step.analysis.arrival_levels;
  for (std::size_t i = 0; i < arrivals.size(); ++i) {
    const double flow = arrivals[i].u * filament_area_mm2;
    j["operating_points"][i]["flow_mm3_s"] = flow;
    if (arrivals[i].n_rising > 0 && arrivals[i].n_falling > 0)
      levels += fmt::format("{}{} mm^3/s: {} s", levels.empty() ? "" : "; ", display_number(flow),
                            display_number(arrivals[i].fit.value("tau_s")));
  }
  if (!levels.empty()) {
    std::string trend;
    if (const auto& tau_trend = step.analysis.level_trends.tau)
      trend = fmt::format(" (tau = a u^b, b = {})", display_number(tau_trend->value("b")));
    r.notes.push_back(fmt::format("flow sweep: tau at each level reached from both sides, {}{}", levels, trend));
  }
  if (const auto& m = step.whole_record.model) {
    add_whole_record_rows(r, *m, {display_number(m->model.reference_input * filament_area_mm2) + " mm^3/s"});
    return;
  }
  const std::string p = "liquefier.step.pooled.params.";
  r.row("liquefier time constant tau (step response)", p + "tau_s.value", "s", p + "tau_s.ci95");
  r.row("liquefier dead time theta (step response)", p + "theta_s.value", "s", p + "theta_s.ci95");
  r.row("liquefier gain K (step response)", p + "K.value", "N/(mm/s)", p + "K.ci95");
}

void add_freq(RunRecord& r, const FreqOutcome& chirp, const ExperimentRuns& runs,
              const std::optional<StepOutcome>& step, double filament_area_mm2) {
  const auto& plan = runs.chirp;
  r.res()["liquefier"]["freq"] = analysis_results(chirp);
  r.res()["liquefier"]["chirp_plan"] = {{"expected_tau_s", plan.expected_tau_s},
                                        {"basis", runs.chirp_basis},
                                        {"corner_hz", plan.corner_hz},
                                        {"freq_min_hz", plan.freq_min_hz},
                                        {"freq_max_hz", plan.freq_max_hz},
                                        {"duration_s", plan.duration_s},
                                        {"settle_s", plan.settle_s}};
  r.plot["bode"] = bode_plotdata(chirp);
  const auto& bb = *chirp.broadband;
  const fitting::FitResult* fit = chirp.reported_fit();
  if (const auto& m = chirp.whole_record.model) {
    // The chirp's record identifies the same model as the flow sweep's (the transfer function
    // fitted to it, a linear model of a liquefier whose tau follows the flow, stays in the
    // results): its tau at its own reference feed.
    r.row(fmt::format("liquefier time constant tau at {} mm^3/s (chirp, whole-record model)",
                      display_number(m->model.reference_input * filament_area_mm2)),
          "liquefier.freq.whole_record.tau_ref_s.value", "s", "liquefier.freq.whole_record.tau_ref_s.ci95");
  } else if (fit != nullptr) {
    const std::string p = "liquefier.freq.fit.params.";
    r.row(fmt::format("tau from the frequency response (chirp, {})", chirp.reported_fit_method()), p + "tau_s.value",
          "s", p + "tau_s.ci95");
  }
  r.notes.push_back(
      fmt::format("chirp sized from {}: corner {} Hz, {}-{} Hz over {} s; analysed from {} s up to {} Hz in Welch "
                  "segments of {} samples ({} Hz bins)",
                  runs.chirp_basis, display_number(plan.corner_hz), display_number(plan.freq_min_hz),
                  display_number(plan.freq_max_hz), display_number(plan.duration_s), display_number(bb.start_s),
                  display_number(bb.fmax_hz), bb.segment_length,
                  display_number(bb.sample_rate_hz / static_cast<double>(bb.segment_length))));
  Estimate by_step, by_freq;
  if (step && fit != nullptr &&
      step_tau_for_freq(step_design_input(*step, ""), freq_design_input(chirp, ""), by_step) &&
      calibrate_estimate(fit->param("tau_s"), "frequency response", by_freq)) {
    auto a =
        compare_estimates("liquefier time constant tau", "s", by_step, by_freq, fitting::equivalence_margin("tau_s"));
    a["id"] = "tau";
    if (!a.at("agree").get<bool>()) r.env.warn(a.at("statement").get<std::string>());
    r.agreement.push_back(a);
  }
}

void add_axes(RunRecord& r, const Identification& id) {
  for (const auto& [axis, shaper] : id.shapers) {
    const std::string label(1, axis);
    const ShaperAxis* result = shaper.axis(label);
    if (result == nullptr) throw InputError("'tunekit shaper' found no " + label + " axis in its file");
    r.res()["axes"][label] = shaper_axis_json(shaper, *result);
    r.plot["psd_" + label] = psd_plotdata(shaper, *result);
    const std::string base = "axes." + label;
    r.row(label + " resonance frequency", base + ".modes[0].freq_hz", "Hz", base + ".modes[0].freq_ci95");
    r.row(label + " damping ratio", base + ".modes[0].zeta", "1", base + ".modes[0].zeta_ci95");
    r.row(label + " shaper frequency", base + ".recommended.freq_hz", "Hz", "", "designed");
    r.row(label + " max acceleration", base + ".proposed_max_accel_mm_s2", "mm/s^2", "",
          r.res()["axes"][label].contains("proposed_max_accel_note") ? "the printer's limit (the shaper allows more)"
                                                                     : "designed");
  }
}

void add_compensators(RunRecord& r, const CompensatorDesign& design, const std::string& run_dir) {
  const ExportOutcome& ex = design.exported;
  if (design.marlin_ft_live) r.res()["firmware_ft_motion"] = "active (M493): settings written as M493";
  r.res()["compensators"] = analysis_results(ex);
  // The report draws the advance the liquefier needs against flow (the export's flow design).
  if (ex.flow) r.plot["flow_advance"] = ex.flow->to_json();
  r.res()["config_diff"] = ex.change.diff;
  if (ex.settings.pa_k_s) {
    const auto& ci = ex.pa_k_ci95;  // export's own interval: `tunekit export` prints the same
    if (ci) {
      r.res()["compensators"]["pa_k_ci95"] = {ci->first, ci->second};
      r.row("pressure advance K", "compensators.settings.pa_k_s", "s", "compensators.pa_k_ci95");
    } else {
      r.row("pressure advance K", "compensators.settings.pa_k_s", "s", "", "designed (K = tau)");
    }
  }
  if (ex.settings.pa_smooth_s)
    r.row("advance smoothing time", "compensators.settings.pa_smooth_s", "s", "", "designed");
  if (ex.design)
    for (const auto& n : ex.design->notes) r.notes.push_back(n);
  for (const auto& w : to_envelope(ex).warnings()) {
    nlohmann::json wj = w;
    strip_prefix(wj, run_dir + "/");
    r.env.warn(wj.get<std::string>());
  }
}

nlohmann::json reproduce_json(const Identification& id) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& rep : id.reproduce)
    out.push_back({{"analysis", rep.analysis}, {"json", rep.json}, {"command", rep.command()}});
  return out;
}

RunRecord build_record(const CalibrationPlan& plan, const ExperimentRuns& runs, const Identification& id,
                       const CompensatorDesign& design) {
  RunRecord r;
  const CalibrateArgs& a = plan.options;
  // Inputs are recorded relative to the run directory: the run can move, and two runs of the
  // same machine give byte-identical results.json files.
  // The digests the analyses took of the bytes they read (the files are not read again).
  for (const auto& in : id.inputs)
    r.env.add_input_digest(fs::relative(in.path, plan.run_dir).generic_string(), in.sha256, in.size_bytes);
  r.env.set_options({{"machine", a.machine},
                     {"profile", a.profile.empty() ? "builtin" : a.profile},
                     {"firmware", a.firmware},
                     {"config", a.config},
                     {"write", a.write},
                     {"sim", a.sim_options}});
  r.res()["machine"] = plan.profile.profile.name;
  if (id.camera) add_camera(r, *id.camera, *id.step, plan.profile.profile.filament_area_mm2());
  else if (id.step) add_load_cell_step(r, *id.step, plan.profile.profile.filament_area_mm2());
  if (id.freq) add_freq(r, *id.freq, runs, id.step, plan.profile.profile.filament_area_mm2());
  add_axes(r, id);
  add_compensators(r, design, plan.run_dir);
  r.res()["summary"] = r.summary;
  r.res()["agreement"] = r.agreement;
  r.res()["notes"] = r.notes;
  r.res()["reproduce"] = reproduce_json(id);
  strip_prefix(r.res(), plan.run_dir + "/");
  return r;
}

// RUN_DIR/analysis/README: what each file is and the command that reproduces it.
std::string analysis_readme(const Identification& id) {
  std::ostringstream os;
  os << "The analyses of this calibration. Each NAME.json holds the results of the tunekit command below,\n"
        "run from the run directory (the directory above this one) with that command's defaults; add --json\n"
        "to print its JSON or --json-file FILE to write it (the same results; only the input paths differ).\n\n";
  for (const auto& rep : id.reproduce)
    os << rep.json.substr(rep.json.find('/') + 1) << ": " << rep.what << "\n    " << rep.command() << "\n\n";
  os << "export.json: the compensators and the configuration change, designed by tunekit export from\n"
        "    step.json and the shaper_*.json files (results.json: compensators)\n";
  return os.str();
}

}  // namespace

int write_run(const CalibrationPlan& plan, const ExperimentRuns& runs, const Identification& identified,
              const CompensatorDesign& design, Progress& progress, CliContext& ctx) {
  RunRecord r = build_record(plan, runs, identified, design);
  progress.begin("write report", 2);
  core::write_file_atomic(plan.run_dir + "/analysis/README", analysis_readme(identified));
  core::write_file_atomic(plan.run_dir + "/results.json", r.env.dump());
  core::write_file_atomic(plan.run_dir + "/plotdata.json", r.plot.dump() + "\n");
  const ReportOutcome written = compute_report({plan.run_dir});
  const std::string& report = written.html_path;
  progress.end(report);
  // A plot library that failed (a memory cap): one line; the report holds everything but the figures.
  const auto failed = std::count_if(written.images.begin(), written.images.end(),
                                    [](const ReportImage& i) { return !i.failure.empty(); });
  if (failed > 0)
    ctx.err << fmt::format(
        "tunekit: warning: {} of the report's {} figures: {}; the results and the report's text are complete\n", failed,
        written.images.size(), std::find_if(written.images.begin(), written.images.end(), [](const ReportImage& i) {
                                 return !i.failure.empty();
                               })->failure);
  if (!plan.options.output.json) print_calibrate_terminal(r.res(), design, report, ctx.out);
  OutputOptions output = plan.output;
  output.record_source = plan.run_dir;
  return emit(r.env, output, ctx);
}

}  // namespace tunekit::calibration
