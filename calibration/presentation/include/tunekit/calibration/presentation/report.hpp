#pragma once
// The calibration report: one self-contained HTML file (plots embedded as SVG data URIs, the
// line-width photo as a PNG one; no scripts, no external files, and a Content-Security-Policy
// that forbids any request leaving the file) built from a run directory's results.json and
// plotdata.json. `tunekit report RUN_DIR` rebuilds it at any time.
//
// The report is rendered from a run's typed record (calibration_record.hpp): by `tunekit
// calibrate` from the record it has just made, by `tunekit report` from the record read back from
// results.json and plotdata.json, so both give the same report.
//
// results.json is a tunekit envelope. `results.summary` lists the rows of the summary table as
// {label, path, unit, ci_path?, basis?}: `path` points at a number inside `results`
// (e.g. "compensators.settings.pa_k_s"), `ci_path` at its 95 % interval [lo, hi]; a row
// without an interval says why in `basis` ("designed", "fixed"). `results.agreement` lists
// quantities measured two ways (see agreement.hpp); `results.notes` informational lines.
// Every warning is shown with a one-line "what to do" (warning_advice.hpp).
// plotdata.json holds the series of each plot:
//   step:      {t_s[], u[], y[], y_fit[] (each step's fit over its step, null elsewhere), u_label, y_label,
//              y_model[] (the whole-record model's output over the record) and model_label, or
//              model_missing (why there is no model)}
//   bode:      {freq_hz[], mag_db[], phase_deg[], coherence[], model: {freq_hz[], mag_db[], phase_deg[], label}}
//   psd_<axis>: {freq_hz[], psd[], modes: [{freq_hz}], shapers: [{type, freq_hz[], response[]}],
//              recommended: {type, freq_hz}}
//   flow_advance: {curve: [{flow_mm3_s, tau_s, K_need_s, K_lo_s, K_hi_s, K_kalico_s}], kalico:
//              {pressure_advance_model}, single: {K_s}, design_flow_mm3_s, orca: [{flow_mm3_s, K_s}]}
//   overshoot_grid: {tolerance_mm, cells: [{input_shaping, speed_mm_s, accel_mm_s2, overshoot_mm,
//              completion_time_s, figure_of_merit}]}
//   viscosity: {series: [{temperature_K, shear_rate_1_s[], viscosity_Pa_s[], fit_shear_rate_1_s[],
//              fit_viscosity_Pa_s[]}]}
//   linewidth: {s_mm[], width_mm[], setpoint_mm[], overlay_png: "file name in the run directory"}
//   thermal:   the step's layout for the hot end's record (calibrate --thermal): u the heater's duty,
//              y the measured temperature, y_model the thermal model's (fitted, then predicted over
//              the held-out part)
// Plots whose data are absent are left out.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include "tunekit/calibration/results/json_access.hpp"  // json_at(): the summary rows' dotted paths
#include "tunekit/calibration/presentation/plots.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/calibration/results/display_number.hpp"  // display_number(), display_interval()
#include "tunekit/calibration/results/plot_data.hpp"

namespace tunekit::calibration {

/// The record's input, its output with the whole-record model (colour kWholeRecordModelColor) and
/// each step's fit (colour 2, dashed), and the residuals; without the model the output panel's
/// title says why.
Figure step_figure(const StepPlot& d);
/// The step plot's sentence on a missing whole-record model ("whole-record model not fitted:
/// <reason>"); empty when the plot has the model.
std::string step_model_note(const StepPlot& d);
/// The palette colour of the whole-record model's curves.
constexpr int kWholeRecordModelColor = 5;
Figure bode_figure(const BodePlot& d);
Figure psd_figure(const PsdPlot& d, const std::string& axis);
Figure viscosity_figure(const ViscosityPlot& d);
Figure linewidth_figure(const LinewidthPlot& d);
Figure overshoot_grid_figure(const OvershootGridPlot& d);

struct ReportImage {
  std::string id;  ///< e.g. "step", "psd_x"
  std::string caption;
  std::string path;  ///< the image file (.svg plot or .png photo); empty when not drawn
  /// Why the figure was not drawn (the plot library failed, e.g. under a memory cap): the report
  /// says so in its place and keeps everything else. Empty when it was drawn.
  std::string failure;
  std::string bytes;  ///< the image file's contents, kept from rendering (or reading the photo)
};

/// Renders every plot `plots` has data for into RUN_DIR/plots/*.svg.
std::vector<ReportImage> render_report_plots(const std::string& run_dir, const ReportPlots& plots);

/// The HTML text of a record and its rendered images.
std::string build_report_html(const CalibrationRecord& record, const std::vector<ReportImage>& images);

}  // namespace tunekit::calibration
