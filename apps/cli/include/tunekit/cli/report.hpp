#pragma once
// The calibration report: one self-contained HTML file (plots embedded as PNG data URIs,
// no scripts, no external files) built from a run directory's results.json and
// plotdata.json. `tunekit report RUN_DIR` rebuilds it at any time.
//
// results.json is a tunekit envelope; its `results.summary` lists the rows of the summary
// table as {label, path, unit}, where `path` points at a number inside `results`
// (e.g. "compensators.pressure_advance.k_s"). plotdata.json holds the series of each plot:
//   step:      {t_s[], u[], y[], y_fit[], u_label, y_label}
//   bode:      {freq_hz[], mag_db[], phase_deg[], coherence[], model: {freq_hz[], mag_db[], phase_deg[]}}
//   psd.<axis>: {freq_hz[], psd[], modes: [{freq_hz}], shapers: [{type, freq_hz[], response[]}]}
//   viscosity: {series: [{temperature_K, shear_rate_1_s[], viscosity_Pa_s[], fit_shear_rate_1_s[], fit_viscosity_Pa_s[]}]}
//   linewidth: {s_mm[], width_mm[], setpoint_mm[], overlay_png: "file name in the run directory"}
// Plots whose data are absent are left out.

#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/cli/plots.hpp"

namespace tunekit::cli {

Figure step_figure(const nlohmann::json& d);
Figure bode_figure(const nlohmann::json& d);
Figure psd_figure(const nlohmann::json& d, const std::string& axis);
Figure viscosity_figure(const nlohmann::json& d);
Figure linewidth_figure(const nlohmann::json& d);
/// overshoot_grid: {tolerance_mm, cells: [{speed_mm_s, accel_mm_s2, overshoot_mm, completion_time_s, figure_of_merit}]}
Figure overshoot_grid_figure(const nlohmann::json& d);

struct ReportImage {
  std::string id;       ///< e.g. "step", "psd_x"
  std::string caption;
  std::string png_path;
};

/// Renders every plot that plotdata.json has data for into RUN_DIR/plots/*.png.
std::vector<ReportImage> render_report_plots(const std::string& run_dir, const nlohmann::json& plotdata);

/// The HTML text for an envelope (results.json contents) and rendered images.
std::string build_report_html(const nlohmann::json& envelope, const std::vector<ReportImage>& images);

/// Reads RUN_DIR/results.json and RUN_DIR/plotdata.json (optional), renders the plots and
/// writes RUN_DIR/report.html atomically. Returns the report's path.
std::string write_report(const std::string& run_dir);

/// Formats a number for display with 4 significant digits ("0.4512", "1.25e+04").
std::string display_number(double v);

/// Looks up "a.b[2].c" in a JSON value; nullptr when absent.
const nlohmann::json* json_at(const nlohmann::json& root, const std::string& path);

}  // namespace tunekit::cli
