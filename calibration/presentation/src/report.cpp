#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/presentation/report_command.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/calibration/results/base64.hpp"
#include "tunekit/calibration/results/warning_advice.hpp"
#include "tunekit/core/json_error_text.hpp"
#include "tunekit/calibration/results/calibration_record.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"

#include "tunekit/calibration/presentation/html.hpp"

namespace tunekit::calibration {
namespace {

// The report's page width and style sheet (tables, figures, warnings, agreements).
constexpr int kReportMaxWidthPx = 1000;
std::string report_css() {
  return html::base_css(kReportMaxWidthPx) +
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.3em "
         ".7em;text-align:left}\n" +
         std::string(html::kTableCss) +
         "figure{margin:1em 0}figure img{max-width:100%;border:1px solid #ddd}figcaption{color:#555;font-size:.9em}\n"
         "pre{background:#f7f7f7;border:1px solid #ddd;padding:.8em;overflow-x:auto;font-size:.85em}\n"
         ".warn{color:#a15c00}.todo{color:#333}.ci{color:#444;font-variant-numeric:tabular-nums}\n"
         ".agree{border-left:4px solid #2c7a2c;padding-left:.6em}.disagree{border-left:4px solid "
         "#b00;padding-left:.6em}\n";
}

// The report's Content-Security-Policy: no request may leave the file.
constexpr const char* kReportCsp =
    "default-src 'none'; img-src data:; style-src 'unsafe-inline'; base-uri 'none'; form-action 'none'";

std::string image_mime(const std::string& path) {
  const auto ext = std::filesystem::path(path).extension().string();
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  throw InputError("a report image must be .svg or .png", path);
}

// render_svg, returning the SVG text it wrote (the plot library writes only to a file): the
// text the report embeds, kept from rendering.
std::string render_svg_text(const Figure& fig, const std::string& path) {
  render_svg(fig, path);
  return read_file_bytes(path);
}

}  // namespace

std::string step_model_note(const StepPlot& d) {
  if (d.has_model()) return "";
  return d.model_missing.empty() ? std::string("no whole-record model in the plot data")
                                 : "whole-record model not fitted: " + d.model_missing;
}

// The hot end's record: the heater's duty, the measured temperature with the model's, and the
// model's residuals (the held-out part's included: there they are the prediction's errors).
Figure thermal_figure(const StepPlot& d) {
  Figure f;
  f.title = "Hot end thermal record";
  Panel in{"Heater duty", "", d.u_label, false, false, {}, 0.6};
  in.series.push_back({"heater duty", d.t_s, d.u, Series::Style::line, 4});
  Panel out{"Temperature and the thermal model", "", d.y_label, false, false, {}, 1.4};
  out.series.push_back({"measured", d.t_s, d.y, Series::Style::line, 1});
  out.series.push_back({d.model_label, d.t_s, d.y_model, Series::Style::line, kWholeRecordModelColor});
  std::vector<double> res(std::min(d.y.size(), d.y_model.size()));
  for (std::size_t i = 0; i < res.size(); ++i) res[i] = d.y[i] - d.y_model[i];
  Panel rp{"Residuals (measured - model)", "time (s)", "residual (degC)", false, false, {}, 0.7};
  rp.series.push_back({"", d.t_s, res, Series::Style::line, kWholeRecordModelColor});
  f.panels = {in, out, rp};
  f.height_px = 760;
  f.share_x = true;
  return f;
}

Figure step_figure(const StepPlot& d) {
  Figure f;
  f.title = "Liquefier step response";
  Panel in{"Input", "", d.u_label, false, false, {}, 0.6};
  in.series.push_back({"commanded", d.t_s, d.u, Series::Style::line, 4});
  const std::string note = step_model_note(d);
  // The panel's title says why the model is missing (shortened to fit above the panel; the
  // caption has it in full).
  constexpr std::size_t kTitleChars = 100;
  std::string title =
      note.empty() ? "Output, the whole-record model and each step's fit" : "Output and step fits; " + note;
  if (title.size() > kTitleChars) title = title.substr(0, kTitleChars - 3) + "...";
  Panel out{title, "", d.y_label, false, false, {}, 1.4};
  out.series.push_back({"measured", d.t_s, d.y, Series::Style::line, 1});
  if (note.empty())
    out.series.push_back({d.model_label, d.t_s, d.y_model, Series::Style::line, kWholeRecordModelColor});
  out.series.push_back({"step fits (each over its step)", d.t_s, d.y_fit, Series::Style::dashed, 2});
  // The residuals of each: the model's over the whole record, the step fits' over their steps.
  auto residuals = [&](const std::vector<double>& fit, const std::string& panel_title, int color) {
    std::vector<double> res(std::min(d.y.size(), fit.size()));
    for (std::size_t i = 0; i < res.size(); ++i) res[i] = d.y[i] - fit[i];
    Panel rp{panel_title, "", "residual", false, false, {}, 0.7};
    rp.series.push_back({"", d.t_s, res, Series::Style::line, color});
    return rp;
  };
  f.panels = {in, out};
  if (note.empty()) {
    f.panels.push_back(residuals(d.y_model, "Residuals of the whole-record model", kWholeRecordModelColor));
    f.panels.push_back(residuals(d.y_fit, "Residuals of the step fits", 3));
    f.height_px = 900;
  } else {
    f.panels.push_back(residuals(d.y_fit, "Residuals", 3));
    f.panels.back().height_weight = 0.8;
    f.height_px = 760;
  }
  f.panels.back().xlabel = "time (s)";
  f.share_x = true;  // one time axis: the step fits' residuals exist only over their steps
  return f;
}

Figure bode_figure(const BodePlot& d) {
  Figure f;
  f.title = "Liquefier frequency response";
  const auto& fr = d.measured.freq_hz;
  Panel mag{"Magnitude", "", "|H| (dB)", true, false, {}, 1.2};
  mag.series.push_back({"measured", fr, d.measured.mag_db, Series::Style::points, 1});
  Panel ph{"Phase", "", "phase (deg)", true, false, {}, 1.0};
  ph.series.push_back({"measured", fr, d.measured.phase_deg, Series::Style::points, 1});
  if (const auto& m = d.model) {
    mag.series.push_back({m->label, m->curve.freq_hz, m->curve.mag_db, Series::Style::line, 2});
    ph.series.push_back({m->label, m->curve.freq_hz, m->curve.phase_deg, Series::Style::line, 2});
  }
  f.panels = {mag, ph};
  if (!d.coherence.empty()) {
    Panel coh{"Coherence", "frequency (Hz)", "coherence", true, false, {}, 0.7};
    coh.series.push_back({"", fr, d.coherence, Series::Style::line, 3});
    f.panels.push_back(coh);
  } else {
    f.panels.back().xlabel = "frequency (Hz)";
  }
  f.height_px = 760;
  return f;
}

Figure psd_figure(const PsdPlot& d, const std::string& axis) {
  Figure f;
  f.title = fmt::format("Axis {}: power spectral density, modes and input shapers", axis);
  Panel p{"Acceleration PSD", "", "PSD ((mm/s^2)^2/Hz)", false, false, {}, 1.3};
  p.series.push_back({"measured", d.freq_hz, d.psd, Series::Style::line, 1});
  double peak = 0;
  for (double v : d.psd) peak = std::isfinite(v) ? std::max(peak, v) : peak;
  int color = 2;
  for (double fm : d.mode_freq_hz) {
    p.series.push_back({fmt::format("mode {:.1f} Hz", fm), {fm, fm}, {0.0, peak}, Series::Style::dashed, color});
    color = color % 8 + 1;
  }
  Panel s{"Shaper response (remaining vibration)", "frequency (Hz)", "fraction", false, false, {}, 1.0};
  int sc = 2;
  // The recommended shaper is marked: named so in the legend, drawn solid; the others dashed.
  const std::string chosen = d.recommended ? d.recommended->type : "";
  for (const auto& sh : d.shapers) {
    const bool is_chosen = sh.type == chosen;
    s.series.push_back(
        {is_chosen ? fmt::format("{} (recommended, {:.1f} Hz)", sh.type, d.recommended->freq_hz) : sh.type, sh.freq_hz,
         sh.response, is_chosen || chosen.empty() ? Series::Style::line : Series::Style::dashed, sc});
    sc = sc % 8 + 1;
  }
  f.panels = {p};
  if (!s.series.empty()) f.panels.push_back(s);
  else f.panels.back().xlabel = "frequency (Hz)";
  f.height_px = 720;
  return f;
}

Figure viscosity_figure(const ViscosityPlot& d) {
  Figure f;
  f.title = "Melt viscosity";
  Panel p{"Viscosity against shear rate", "shear rate (1/s)", "viscosity (Pa s)", true, true, {}, 1.0};
  int c = 1;
  for (const auto& s : d.series) {
    p.series.push_back(
        {fmt::format("{:.0f} K data", s.temperature_K), s.shear_rate_1_s, s.viscosity_Pa_s, Series::Style::points, c});
    p.series.push_back({"", s.fit_shear_rate_1_s, s.fit_viscosity_Pa_s, Series::Style::line, c});
    c = c % 8 + 1;
  }
  f.panels = {p};
  return f;
}

Figure linewidth_figure(const LinewidthPlot& d) {
  Figure f;
  f.title = "Line width profile";
  Panel p{"Width along the line", "arc length (mm)", "width (mm)", false, false, {}, 1.0};
  p.series.push_back({"measured", d.s_mm, d.width_mm, Series::Style::line, 1});
  if (!d.setpoint_mm.empty()) p.series.push_back({"set point", d.s_mm, d.setpoint_mm, Series::Style::dashed, 2});
  f.panels = {p};
  f.height_px = 420;
  return f;
}

std::vector<ReportImage> render_report_plots(const std::string& run_dir, const ReportPlots& pd) {
  std::vector<ReportImage> images;
  const std::string dir = run_dir + "/plots";
  // Each figure's SVG text is kept from rendering: the report embeds it without reading it again.
  auto add = [&](const std::string& id, const std::string& caption, const Figure& fig) {
    const std::string path = dir + "/" + id + ".svg";
    try {
      images.push_back({id, caption, path, {}, render_svg_text(fig, path)});
    } catch (const InputError& e) {
      images.push_back({id, caption, {}, e.message(), {}});  // the report goes on without it
    }
  };
  if (pd.step) {
    const std::string note = step_model_note(*pd.step);
    add("step",
        note.empty() ? "Step response: the record, the whole-record model over all of it, each step's fit over its "
                       "step, and the residuals"
                     : "Step response: the record, each step's fit over its step and the residuals; " + note,
        step_figure(*pd.step));
  }
  if (pd.bode) add("bode", "Bode plot with the fitted model and the coherence", bode_figure(*pd.bode));
  if (pd.thermal && pd.thermal->has_model())
    add("thermal",
        "Hot end: the heater's duty, the measured temperature with the thermal model (fitted, then run on through "
        "the held-out fan and extrusion steps) and its residuals",
        thermal_figure(*pd.thermal));
  for (const auto& [axis, psd] : pd.psd)
    add("psd_" + axis, fmt::format("Axis {}: PSD with identified modes and the candidate shapers' responses", axis),
        psd_figure(psd, axis));
  if (pd.overshoot_grid)
    add("overshoot_grid", "Overshoot, completion time and figure of merit over the speed x acceleration grid",
        overshoot_grid_figure(*pd.overshoot_grid));
  if (pd.flow_advance)
    add("flow_advance", "Advance against flow: the need with its 95 % band, each exported model, the design flow",
        flow_advance_figure(*pd.flow_advance));
  if (pd.viscosity)
    add("viscosity", "Viscosity against shear rate with the fitted model", viscosity_figure(*pd.viscosity));
  if (pd.linewidth) {
    add("linewidth", "Line-width profile", linewidth_figure(*pd.linewidth));
    // The photo with the detected edges and centreline, shown beside its profile.
    if (const std::string& overlay = pd.linewidth->overlay_png; !overlay.empty()) {
      const std::string path = run_dir + "/" + overlay;
      if (!std::filesystem::exists(path))
        throw InputError("the line-width overlay named in plotdata.json is missing", path);
      images.push_back(
          {"linewidth_overlay", "Photo overlay: detected edges and centreline", path, {}, read_file_bytes(path)});
    }
  }
  return images;
}

namespace {

// The "95 % interval" cell of a summary row: [lo, hi], else n/a, or the row's basis.
std::string interval_cell(const SummaryRow& row) {
  if (row.ci_path.empty()) return "<td class=\"ci\">" + html::escape(row.basis) + "</td>";
  if (!row.estimate.has_interval()) return "<td class=\"ci\">n/a</td>";
  return fmt::format("<td class=\"ci\" data-path=\"{}\">{}</td>", html::escape(row.ci_path),
                     display_interval(row.estimate.ci95_lo, row.estimate.ci95_hi));
}

void summary_html(const CalibrationRecord& r, std::ostream& h) {
  h << "<h2>Summary</h2>\n<table id=\"summary\">\n"
    << "<tr><th>quantity</th><th>value</th><th>95 % interval</th><th>unit</th></tr>\n";
  for (const auto& row : r.summary) {
    if (!row.estimate.has_value()) continue;
    h << "<tr><td>" << html::escape(row.label) << "</td><td class=\"num\" data-path=\"" << html::escape(row.path)
      << "\" data-value=\"" << nlohmann::json(row.estimate.value).dump() << "\">" << display_number(row.estimate.value)
      << "</td>" << interval_cell(row) << "<td>" << html::escape(row.unit) << "</td></tr>\n";
  }
  h << "</table>\n";
}

void agreements_html(const CalibrationRecord& r, std::ostream& h) {
  if (r.agreements.empty()) return;
  h << "<h2>Methods compared</h2>\n";
  for (const auto& a : r.agreements)
    h << "<p class=\"" << (a.agree ? "agree" : "disagree") << "\" id=\"agreement-"
      << html::escape(a.id.empty() ? std::string("quantity") : a.id) << "\" data-agree=\""
      << (a.agree ? "true" : "false") << "\">" << html::escape(a.statement) << "</p>\n";
}

void warnings_and_notes_html(const CalibrationRecord& r, std::ostream& h) {
  if (!r.warnings.empty()) {
    h << "<h2>Warnings</h2>\n<ul id=\"warnings\">\n";
    for (const auto& text : r.warnings)
      h << "<li class=\"warn\">" << html::escape(text)
        << "<br><span class=\"todo\">What to do: " << html::escape(advice_for_warning(text)) << "</span></li>\n";
    h << "</ul>\n";
  }
  if (!r.notes.empty()) {
    h << "<h2>Notes</h2>\n<ul id=\"notes\">\n";
    for (const auto& n : r.notes) h << "<li>" << html::escape(n) << "</li>\n";
    h << "</ul>\n";
  }
}

void images_html(const std::vector<ReportImage>& images, std::ostream& h) {
  if (!images.empty()) h << "<h2>Plots</h2>\n";
  for (const auto& img : images) {
    if (!img.failure.empty()) {
      h << "<figure id=\"plot-" << img.id << "\"><figcaption>" << html::escape(img.caption) << " ("
        << html::escape(img.failure) << ")</figcaption></figure>\n";
      continue;
    }
    h << "<figure id=\"plot-" << img.id << "\"><img alt=\"" << html::escape(img.caption)
      << "\" src=\"data:" << image_mime(img.path) << ";base64," << base64(img.bytes) << "\"><figcaption>"
      << html::escape(img.caption) << "</figcaption></figure>\n";
  }
}

}  // namespace

std::string build_report_html(const CalibrationRecord& r, const std::vector<ReportImage>& images) {
  std::ostringstream h;
  // Nothing may leave the file: no scripts, no fetches; images only from data: URIs.
  h << html::head("tunekit calibration report", report_css(), kReportCsp);
  h << "<h1>tunekit calibration report</h1>\n";
  if (!r.machine.empty()) h << "<p>Machine: " << html::escape(r.machine) << "</p>\n";
  if (!r.tool_version.empty())
    h << "<p>tunekit " << html::escape(r.tool_version) << ", command <code>" << html::escape(r.command)
      << "</code></p>\n";
  summary_html(r, h);
  agreements_html(r, h);
  warnings_and_notes_html(r, h);
  images_html(images, h);
  if (!r.config_diff.empty()) h << "<h2>Configuration changes</h2>\n<pre>" << html::escape(r.config_diff) << "</pre>\n";
  h << "</body>\n</html>\n";
  return h.str();
}

ReportOutcome render_report(const std::string& run_dir, const CalibrationRecord& record) {
  ReportOutcome outcome;
  outcome.options = {run_dir};
  outcome.images = render_report_plots(run_dir, record.plots);
  outcome.html_path = run_dir + "/report.html";
  core::write_file_atomic(outcome.html_path, build_report_html(record, outcome.images));
  return outcome;
}

ReportOutcome compute_report(const ReportOptions& options) {
  return render_report(options.run_dir, read_run_record(options.run_dir));
}

void print_text(const ReportOutcome& outcome, std::ostream& os) { os << outcome.html_path << "\n"; }

}  // namespace tunekit::calibration
