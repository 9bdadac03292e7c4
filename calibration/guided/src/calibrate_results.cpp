// tunekit calibrate, stage 5: the run's record (calibration_record.hpp), built from the stages'
// typed outcomes: the summary rows with their estimates, the agreements of quantities measured
// two ways, notes, the plots' series, and each analysis' results as its own JSON holds them.
// results.json, plotdata.json, report.html, the terminal's table and, with --record, the history
// are rendered from it; then the analysis README.
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
#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/calibration/commands/design_inputs.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/core/version.hpp"

namespace tunekit::calibration {
namespace {

namespace fs = std::filesystem;

// The record and the envelope results.json is written into (command, options, inputs).
struct RunRecord {
  Envelope env{"calibrate"};
  CalibrationRecord rec;
  nlohmann::json& details() { return rec.details; }
  // A summary row with a 95 % interval, recorded in results.json at `path` and `ci_path`.
  void row(const std::string& label, const ValueEstimate& e, const std::string& unit, const std::string& path,
           const std::string& ci_path) {
    rec.summary.push_back({label, e, unit, "", path, ci_path});
  }
  // A summary row without an interval: `basis` says why.
  void row_basis(const std::string& label, double value, const std::string& unit, const std::string& path,
                 const std::string& basis) {
    rec.summary.push_back({label, {value}, unit, basis, path, ""});
  }
  void agreement(Agreement a, const std::string& id) {
    a.id = id;
    if (!a.agree) rec.warnings.push_back(a.statement);
    rec.agreements.push_back(std::move(a));
  }
};

ValueEstimate estimate_of(const fitting::Param& p) { return {p.value, p.ci95_lo, p.ci95_hi}; }

// A fitted parameter's estimate; NaN when the fit has no such parameter.
ValueEstimate param_estimate(const fitting::FitResult& f, const std::string& name) {
  for (const auto& p : f.params)
    if (p.name == name) return estimate_of(p);
  return {};
}

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
  const auto& f = m.model.fit;
  r.row(fmt::format("liquefier time constant tau at {} ({})", w.where, w.model), param_estimate(f, "tau_ref_s"), "s",
        p + "tau_ref_s.value", p + "tau_ref_s.ci95");
  if (!f.param("b").fixed)
    r.row(fmt::format("tau's flow exponent b (tau = a u^b, {})", w.model), param_estimate(f, "b"), "1", p + "b.value",
          p + "b.ci95");
  r.row(fmt::format("liquefier dead time theta ({})", w.model), param_estimate(f, "theta_s"), "s", p + "theta_s.value",
        p + "theta_s.ci95");
  const bool flow_sensor = m.model.sensor == fitting::LiquefierSensor::flow;
  r.row(fmt::format("{} ({})", flow_sensor ? w.gain : "force per stored filament g", w.model), param_estimate(f, "g"),
        f.param("g").unit, p + "model.params.g.value", p + "model.params.g.ci95");
}

// The pooled step fit's rows, when the whole-record model could not be fitted: tau, theta and the
// gain (`gain_label`, `gain_unit`) of the step fits of `source` ("step response", "line widths").
void add_pooled_rows(RunRecord& r, const std::optional<fitting::FitResult>& pooled, const std::string& source,
                     const std::string& gain_label, const std::string& gain_unit) {
  const std::string p = "liquefier.step.pooled.params.";
  const fitting::FitResult f = pooled.value_or(fitting::FitResult{});
  r.row(fmt::format("liquefier time constant tau ({})", source), param_estimate(f, "tau_s"), "s", p + "tau_s.value",
        p + "tau_s.ci95");
  r.row(fmt::format("liquefier dead time theta ({})", source), param_estimate(f, "theta_s"), "s", p + "theta_s.value",
        p + "theta_s.ci95");
  r.row(fmt::format("{} ({})", gain_label, source), param_estimate(f, "K"), gain_unit, p + "K.value", p + "K.ci95");
}

// The camera path's two dead times: the line test's (its whole-record model's, else its pooled
// fit's) and the one the ring's phase implies with the lines' tau, which does not depend on where
// the photo places the lines on their paths (docs/calibrate.md). They differ when that placement is
// off, or the ring's start direction.
void add_camera_theta_agreement(RunRecord& r, const CameraAnalysis& cam, const StepOutcome& widths) {
  if (!cam.ring || !cam.ring_prediction) return;
  const RingPrediction& ring = *cam.ring_prediction;
  if (!std::isfinite(ring.theta_from_phase_ci95_lo_s) || !std::isfinite(ring.theta_from_phase_ci95_hi_s)) return;
  const Estimate by_ring{"ring test's phase", ring.theta_from_phase_s, ring.theta_from_phase_ci95_lo_s,
                         ring.theta_from_phase_ci95_hi_s};
  const fitting::FitResult* lines_fit = widths.whole_record.model ? &widths.whole_record.model->model.fit
                                        : widths.analysis.pooled  ? &*widths.analysis.pooled
                                                                  : nullptr;
  Estimate by_lines;
  if (lines_fit == nullptr || !calibrate_estimate(lines_fit->param("theta_s"), "line test", by_lines)) return;
  r.agreement(
      compare_estimates("liquefier dead time theta", "s", by_lines, by_ring, fitting::equivalence_margin("theta_s")),
      "theta");
}

// The ring's results as results.json holds them: the measurement and, when made, the prediction.
nlohmann::json camera_results(const CameraAnalysis& cam) {
  nlohmann::json j = cam.results;
  if (!cam.ring_prediction || !j.contains("ring")) return j;
  const RingPrediction& p = *cam.ring_prediction;
  auto interval = [](double lo, double hi) {
    return std::isfinite(lo) && std::isfinite(hi) ? nlohmann::json{lo, hi} : nlohmann::json(nullptr);
  };
  auto& ring = j["ring"];
  ring["model_gain"] = p.model_gain;
  ring["model_phase_deg"] = p.model_phase_deg;
  ring["model_phase_ci95_deg"] = interval(p.model_phase_ci95_lo_deg, p.model_phase_ci95_hi_deg);
  ring["theta_from_phase_s"] = p.theta_from_phase_s;
  ring["theta_from_phase_ci95_s"] = interval(p.theta_from_phase_ci95_lo_s, p.theta_from_phase_ci95_hi_s);
  return j;
}

void add_ring_rows(RunRecord& r, const CameraAnalysis& cam) {
  const vision::RingResult& ring = *cam.ring;
  const std::string p = "liquefier.camera.ring.";
  r.row_basis("ring frequency", ring.freq_hz, "Hz", p + "freq_hz", "set by the test (N v / (2 pi R))");
  r.row("ring gain (measured)", {ring.gain, ring.gain_ci95[0], ring.gain_ci95[1]}, "1", p + "gain", p + "gain_ci95");
  r.row("ring phase (measured)", {ring.phase_deg, ring.phase_ci95_deg[0], ring.phase_ci95_deg[1]}, "deg",
        p + "phase_deg", p + "phase_ci95_deg");
  if (const auto& pred = cam.ring_prediction) {
    r.row("ring phase (step model)",
          {pred->model_phase_deg, pred->model_phase_ci95_lo_deg, pred->model_phase_ci95_hi_deg}, "deg",
          p + "model_phase_deg", p + "model_phase_ci95_deg");
    r.row("dead time from the ring's phase",
          {pred->theta_from_phase_s, pred->theta_from_phase_ci95_lo_s, pred->theta_from_phase_ci95_hi_s}, "s",
          p + "theta_from_phase_s", p + "theta_from_phase_ci95_s");
  }
}

void add_camera(RunRecord& r, const CameraAnalysis& cam, const StepOutcome& widths, double filament_area_mm2) {
  r.details()["liquefier"]["step"] = analysis_results(widths);
  r.details()["liquefier"]["camera"] = camera_results(cam);
  r.rec.plots.step = step_plotdata(widths, "feed (mm/s)", "delivered feed (mm/s, from the width)");
  r.rec.plots.linewidth = cam.linewidth_plot;
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
    add_pooled_rows(r, widths.analysis.pooled, "line widths", "width gain K", "1");
  }
  if (cam.ring) add_ring_rows(r, cam);
  add_camera_theta_agreement(r, cam, widths);
  for (const auto& w : cam.warnings) r.rec.warnings.push_back(w);
}

void add_load_cell_step(RunRecord& r, const StepOutcome& step, double filament_area_mm2) {
  auto& j = r.details()["liquefier"]["step"] = analysis_results(step);
  r.rec.plots.step = step_plotdata(step, "feed (mm/s)", "force (N)");
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
    r.rec.notes.push_back(fmt::format("flow sweep: tau at each level reached from both sides, {}{}", levels, trend));
  }
  if (const auto& m = step.whole_record.model) {
    add_whole_record_rows(r, *m, {display_number(m->model.reference_input * filament_area_mm2) + " mm^3/s"});
    return;
  }
  add_pooled_rows(r, step.analysis.pooled, "step response", "liquefier gain K", "N/(mm/s)");
}

// The chirp's plan as results.json records it, and the note that says how it was sized and analysed.
void add_chirp_plan(RunRecord& r, const FreqOutcome& chirp, const ExperimentRuns& runs) {
  const auto& plan = runs.chirp;
  r.details()["liquefier"]["chirp_plan"] = {{"expected_tau_s", plan.expected_tau_s},
                                            {"basis", runs.chirp_basis},
                                            {"corner_hz", plan.corner_hz},
                                            {"freq_min_hz", plan.freq_min_hz},
                                            {"freq_max_hz", plan.freq_max_hz},
                                            {"duration_s", plan.duration_s},
                                            {"settle_s", plan.settle_s}};
  const auto& bb = *chirp.broadband;
  r.rec.notes.push_back(
      fmt::format("chirp sized from {}: corner {} Hz, {}-{} Hz over {} s; analysed from {} s up to {} Hz in Welch "
                  "segments of {} samples ({} Hz bins)",
                  runs.chirp_basis, display_number(plan.corner_hz), display_number(plan.freq_min_hz),
                  display_number(plan.freq_max_hz), display_number(plan.duration_s), display_number(bb.start_s),
                  display_number(bb.fmax_hz), bb.segment_length,
                  display_number(bb.sample_rate_hz / static_cast<double>(bb.segment_length))));
}

void add_freq(RunRecord& r, const FreqOutcome& chirp, const ExperimentRuns& runs,
              const std::optional<StepOutcome>& step, double filament_area_mm2) {
  r.details()["liquefier"]["freq"] = analysis_results(chirp);
  r.rec.plots.bode = bode_plotdata(chirp);
  const fitting::FitResult* fit = chirp.reported_fit();
  if (const auto& m = chirp.whole_record.model) {
    // The chirp's record identifies the same model as the flow sweep's (the transfer function
    // fitted to it, a linear model of a liquefier whose tau follows the flow, stays in the
    // results): its tau at its own reference feed.
    r.row(fmt::format("liquefier time constant tau at {} mm^3/s (chirp, whole-record model)",
                      display_number(m->model.reference_input * filament_area_mm2)),
          param_estimate(m->model.fit, "tau_ref_s"), "s", "liquefier.freq.whole_record.tau_ref_s.value",
          "liquefier.freq.whole_record.tau_ref_s.ci95");
  } else if (fit != nullptr) {
    const std::string p = "liquefier.freq.fit.params.";
    r.row(fmt::format("tau from the frequency response (chirp, {})", chirp.reported_fit_method()),
          param_estimate(*fit, "tau_s"), "s", p + "tau_s.value", p + "tau_s.ci95");
  }
  add_chirp_plan(r, chirp, runs);
  Estimate by_step, by_freq;
  if (step && fit != nullptr &&
      step_tau_for_freq(step_design_input(*step, ""), freq_design_input(chirp, ""), by_step) &&
      calibrate_estimate(fit->param("tau_s"), "frequency response", by_freq))
    r.agreement(
        compare_estimates("liquefier time constant tau", "s", by_step, by_freq, fitting::equivalence_margin("tau_s")),
        "tau");
}

// --thermal: the hot end's model, each parameter with its interval, and the held-out prediction.
void add_thermal(RunRecord& r, const ThermalOutcome& t) {
  r.details()["thermal"] = analysis_results(t);
  StepPlot plot;
  plot.u_label = "heater duty (1)";
  plot.y_label = "temperature (degC)";
  plot.t_s = t.record.t_s;
  plot.u = t.record.heater_duty;
  plot.y = t.record.temp_c;
  plot.y_model = t.fit.predicted_c;
  plot.model_label = "thermal model";
  r.rec.plots.thermal = std::move(plot);
  const auto& f = t.fit.fit;
  const std::string p = "thermal.params.";
  const std::pair<const char*, const char*> rows[] = {
      {"block_heat_capacity_j_per_k", "hot end heat capacity C"},
      {"sensor_responsiveness_per_s", "hot end sensor responsiveness R"},
      {"ambient_transfer_w_per_k", "hot end loss to the ambient A (fan off)"},
      {"fan_transfer_w_per_k", "hot end loss to the ambient F (full fan)"},
      {"filament_heat_capacity_j_per_k_mm", "filament heat capacity H"}};
  for (const auto& [name, label] : rows)
    if (!f.param(name).fixed)
      r.row(label, param_estimate(f, name), f.param(name).unit, p + name + ".value", p + name + ".ci95");
  if (t.fit.held_out_samples > 0)
    r.row_basis("hot end held-out prediction error (RMS)", t.fit.held_out_rms_c, "degC", "thermal.held_out.rms_c",
                "the model run on through the held-out fan and extrusion steps");
}

void add_axes(RunRecord& r, const Identification& id) {
  for (const auto& [axis, shaper] : id.shapers) {
    const std::string label(1, axis);
    const ShaperAxis* result = shaper.axis(label);
    if (result == nullptr) throw InputError("'tunekit shaper' found no " + label + " axis in its file");
    r.details()["axes"][label] = shaper_axis_json(shaper, *result);
    r.rec.plots.psd[label] = psd_plotdata(shaper, *result);
    const std::string base = "axes." + label;
    const auto& modes = result->resonance.modes.modes;
    ValueEstimate freq, zeta;
    if (!modes.empty()) {
      freq = {modes[0].freq_hz, modes[0].freq_ci95_lo, modes[0].freq_ci95_hi};
      zeta = {modes[0].zeta, modes[0].zeta_ci95_lo, modes[0].zeta_ci95_hi};
    }
    r.row(label + " resonance frequency", freq, "Hz", base + ".modes[0].freq_hz", base + ".modes[0].freq_ci95");
    r.row(label + " damping ratio", zeta, "1", base + ".modes[0].zeta", base + ".modes[0].zeta_ci95");
    r.row_basis(label + " shaper frequency", result->choice.recommended.freq_hz, "Hz", base + ".recommended.freq_hz",
                "designed");
    const ProposedAccel accel = proposed_max_accel(shaper, *result);
    r.row_basis(label + " max acceleration", accel.mm_s2, "mm/s^2", base + ".proposed_max_accel_mm_s2",
                accel.capped ? "the printer's limit (the shaper allows more)" : "designed");
  }
}

void add_compensators(RunRecord& r, const CompensatorDesign& design, const std::string& run_dir) {
  const ExportOutcome& ex = design.exported;
  if (design.marlin_ft_live) r.details()["firmware_ft_motion"] = "active (M493): settings written as M493";
  r.details()["compensators"] = analysis_results(ex);
  // The report draws the advance the liquefier needs against flow (the export's flow design).
  if (ex.flow) r.rec.plots.flow_advance = flow_advance_plot(*ex.flow);
  r.rec.config_diff = ex.change.diff;
  if (const auto& k = ex.settings.pa_k_s) {
    const auto& ci = ex.pa_k_ci95;  // export's own interval: `tunekit export` prints the same
    if (ci) {
      r.details()["compensators"]["pa_k_ci95"] = {ci->first, ci->second};
      r.row("pressure advance K", {*k, ci->first, ci->second}, "s", "compensators.settings.pa_k_s",
            "compensators.pa_k_ci95");
    } else {
      r.row_basis("pressure advance K", *k, "s", "compensators.settings.pa_k_s", "designed (K = tau)");
    }
  }
  if (const auto& smooth = ex.settings.pa_smooth_s)
    r.row_basis("advance smoothing time", *smooth, "s", "compensators.settings.pa_smooth_s", "designed");
  if (ex.design)
    for (const auto& n : ex.design->notes) r.rec.notes.push_back(n);
  for (const auto& w : to_envelope(ex).warnings()) {
    nlohmann::json wj = w;
    strip_prefix(wj, run_dir + "/");
    r.rec.warnings.push_back(wj.get<std::string>());
  }
}

nlohmann::json reproduce_json(const Identification& id) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& rep : id.reproduce)
    out.push_back({{"analysis", rep.analysis}, {"json", rep.json}, {"command", rep.command()}});
  return out;
}

// Paths inside the run directory, as results.json writes them (strip_prefix): in every string of
// the record's results (not its warnings, which keep what the analyses said).
void strip_run_dir(CalibrationRecord& rec, const std::string& prefix) {
  auto strip = [&](std::string& s) {
    nlohmann::json j = s;
    strip_prefix(j, prefix);
    s = j.get<std::string>();
  };
  strip(rec.machine);
  for (auto& row : rec.summary)
    for (auto* s : {&row.label, &row.unit, &row.basis, &row.path, &row.ci_path}) strip(*s);
  for (auto& a : rec.agreements)
    for (auto* s : {&a.id, &a.quantity, &a.unit, &a.a.method, &a.b.method, &a.margin_basis, &a.verdict, &a.statement})
      strip(*s);
  for (auto& n : rec.notes) strip(n);
  strip(rec.config_diff);
  strip_prefix(rec.details, prefix);
}

/// A fit's parameters as (estimate, 95 % half-width).
std::map<std::string, std::pair<double, double>> half_widths(const fitting::FitResult& f) {
  std::map<std::string, std::pair<double, double>> out;
  for (const auto& p : f.params)
    if (!p.fixed) out[p.name] = {p.value, 0.5 * (p.ci95_hi - p.ci95_lo)};
  return out;
}

/// What one experiment achieved: each quantity's (estimate, 95 % half-width), and the prediction
/// made at those estimates from the experiment as it ran (how well the information was
/// computed, whatever the prior). Empty when its analysis has no such quantities.
struct Achieved {
  std::map<std::string, std::pair<double, double>> intervals;
  std::optional<protocols::ExperimentPrediction> at_estimate;
};

Achieved achieved_by(const CalibrationPlan& plan, const PlannedExperiment& e, const protocols::Experiment& ran,
                     const Identification& id) {
  Achieved a;
  const WholeRecordResult* record = e.protocol == "liquefier-flow-sweep" && id.step ? &id.step->whole_record
                                    : e.protocol == "liquefier-chirp" && id.freq    ? &id.freq->whole_record
                                                                                    : nullptr;
  if (record && record->model) {
    a.intervals = half_widths(record->model->model.fit);
    a.at_estimate = protocols::predict_liquefier_record(
        ran, liquefier_prior_from(plan.liquefier_prior, *record->model, "this experiment's whole-record model"));
  }
  if (e.protocol != "axis-sweep" || e.axis.empty()) return a;
  const auto s = id.shapers.find(e.axis[0]);
  const ShaperAxis* axis = s != id.shapers.end() ? s->second.axis(e.axis) : nullptr;
  if (!axis || axis->resonance.modes.modes.empty()) return a;
  const auto& modes = axis->resonance.modes;
  const auto& m = modes.modes[modes.dominant >= 0 ? static_cast<std::size_t>(modes.dominant) : 0];
  a.intervals["freq_hz"] = {m.freq_hz, 0.5 * (m.freq_ci95_hi - m.freq_ci95_lo)};
  a.intervals["zeta"] = {m.zeta, 0.5 * (m.zeta_ci95_hi - m.zeta_ci95_lo)};
  protocols::AxisPrior prior = plan.axis_prior;
  prior.freq_hz = m.freq_hz;
  prior.zeta = m.zeta;
  a.at_estimate = protocols::predict_axis_sweep(ran, prior);
  return a;
}

/// Each quantity's achieved 95 % half-width beside the one predicted before the run and the one
/// predicted at the estimates.
nlohmann::json achieved_beside_predicted(const protocols::ExperimentPrediction& predicted, const Achieved& achieved) {
  nlohmann::json q = nlohmann::json::object();
  for (const auto& i : predicted.intervals) {
    auto& j = q[i.quantity] = {{"predicted_half_width", i.half_width}, {"prior", i.value}};
    const auto it = achieved.intervals.find(i.quantity);
    if (it == achieved.intervals.end() || !std::isfinite(it->second.second)) continue;
    j["achieved_half_width"] = it->second.second;
    j["estimate"] = it->second.first;
    j["achieved_over_predicted"] = it->second.second / i.half_width;
    if (const auto* at = achieved.at_estimate ? achieved.at_estimate->find(i.quantity) : nullptr) {
      j["predicted_at_estimate_half_width"] = at->half_width;
      j["achieved_over_predicted_at_estimate"] = it->second.second / at->half_width;
    }
  }
  return {{"quantities", q}, {"basis", predicted.basis}};
}

/// results.experiment_design: each experiment's machine time and its parameters' predicted and
/// achieved intervals; a note line for the report with the ratio of the two.
void add_design_check(RunRecord& r, const CalibrationPlan& plan, const ExperimentRuns& runs, const Identification& id) {
  nlohmann::json exps = nlohmann::json::object();
  std::string note;
  double total_s = 0;
  for (const auto& e : plan.experiments) {
    const auto run = runs.runs.find(e.name);
    if (run == runs.runs.end()) continue;
    total_s += run->second.experiment.estimated_duration_s;
    auto& j =
        exps[e.name] = {{"protocol", e.protocol}, {"machine_time_s", run->second.experiment.estimated_duration_s}};
    // A coarse pass reports no interval: it locates the mode its fine pass is designed and predicted from.
    if (const auto located = runs.fine_modes.find(e.locates); located != runs.fine_modes.end())
      j["locates"] = {{"fine_pass", e.locates},
                      {"freq_hz", located->second.freq_hz},
                      {"zeta", located->second.zeta},
                      {"basis", located->second.basis}};
    const auto p = runs.predicted.find(e.name);
    if (p == runs.predicted.end()) continue;
    j["predicted"] = achieved_beside_predicted(p->second, achieved_by(plan, e, run->second.experiment, id));
    for (const auto& [q, v] : j["predicted"]["quantities"].items())
      if (v.contains("achieved_over_predicted"))
        note += fmt::format("{}{} {} {:.2f}", note.empty() ? "" : ", ", e.name, q,
                            v["achieved_over_predicted"].get<double>());
  }
  r.details()["experiment_design"] = {{"experiments", exps}, {"machine_time_s", total_s}};
  if (!note.empty())
    r.rec.notes.push_back(
        fmt::format("experiment design: {:.1f} s of machine time; each interval achieved over the "
                    "one predicted before the run: {}",
                    total_s, note));
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
  r.rec.tool_version = core::kVersion;
  r.rec.machine = plan.profile.profile.name;
  if (id.camera) add_camera(r, *id.camera, *id.step, plan.profile.profile.filament_area_mm2());
  else if (id.step) add_load_cell_step(r, *id.step, plan.profile.profile.filament_area_mm2());
  if (id.freq) add_freq(r, *id.freq, runs, id.step, plan.profile.profile.filament_area_mm2());
  add_axes(r, id);
  if (id.thermal) add_thermal(r, *id.thermal);
  add_compensators(r, design, plan.run_dir);
  add_design_check(r, plan, runs, id);
  r.details()["reproduce"] = reproduce_json(id);
  strip_run_dir(r.rec, plan.run_dir + "/");
  write_record_results(r.rec, r.env);
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
  core::write_file_atomic(plan.run_dir + "/plotdata.json", plotdata_json(r.rec.plots).dump() + "\n");
  const ReportOutcome written = render_report(plan.run_dir, r.rec);
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
  if (!plan.options.output.json) print_calibrate_terminal(r.rec, design, report, ctx.out);
  OutputOptions output = plan.output;
  output.record_source = plan.run_dir;
  return emit(r.env, output, ctx);
}

}  // namespace tunekit::calibration
