#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/results/results_json.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <openssl/evp.h>

#include "tunekit/calibration/results/warning_advice.hpp"
#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/file_bytes.hpp"

#include "tunekit/calibration/presentation/html.hpp"

namespace tunekit::calibration {
namespace {

std::vector<double> vec(const nlohmann::json& d, const char* key) {
  if (!d.contains(key) || !d[key].is_array()) return {};
  std::vector<double> v;
  v.reserve(d[key].size());
  for (const auto& x : d[key]) v.push_back(x.is_number() ? x.get<double>() : std::nan(""));
  return v;
}

std::string base64(std::string_view bytes) {
  std::string out(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int n = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(out.data()),
                                reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<int>(bytes.size()));
  out.resize(static_cast<std::size_t>(n));
  return out;
}

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

}  // namespace

std::string display_number(double v) {
  if (!std::isfinite(v)) return "n/a";
  return fmt::format("{:.4g}", v);
}

std::string display_interval(double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return fmt::format("[{}, {}]", display_number(lo), display_number(hi));
  // 8 significant digits tell apart bounds 1e-7 apart relative to their size: an interval narrower
  // than that is a measurement's rounding, not information, and prints as equal bounds.
  constexpr int kMaxDigits = 8;
  int digits = 4;
  while (digits < kMaxDigits && lo != hi && fmt::format("{:.{}g}", lo, digits) == fmt::format("{:.{}g}", hi, digits))
    ++digits;
  return fmt::format("[{:.{}g}, {:.{}g}]", lo, digits, hi, digits);
}

std::string step_model_note(const nlohmann::json& d) {
  if (d.contains("y_model")) return "";
  const std::string why = d.value("model_missing", std::string());
  return why.empty() ? std::string("no whole-record model in the plot data") : "whole-record model not fitted: " + why;
}

Figure step_figure(const nlohmann::json& d) {
  Figure f;
  f.title = "Liquefier step response";
  Panel in{"Input", "", d.value("u_label", std::string("input")), false, false, {}, 0.6};
  in.series.push_back({"commanded", vec(d, "t_s"), vec(d, "u"), Series::Style::line, 4});
  const std::string note = step_model_note(d);
  // The panel's title says why the model is missing (shortened to fit above the panel; the
  // caption has it in full).
  constexpr std::size_t kTitleChars = 100;
  std::string title =
      note.empty() ? "Output, the whole-record model and each step's fit" : "Output and step fits; " + note;
  if (title.size() > kTitleChars) title = title.substr(0, kTitleChars - 3) + "...";
  Panel out{title, "", d.value("y_label", std::string("output")), false, false, {}, 1.4};
  out.series.push_back({"measured", vec(d, "t_s"), vec(d, "y"), Series::Style::line, 1});
  if (note.empty())
    out.series.push_back({d.value("model_label", std::string("whole-record model")), vec(d, "t_s"), vec(d, "y_model"),
                          Series::Style::line, kWholeRecordModelColor});
  out.series.push_back({"step fits (each over its step)", vec(d, "t_s"), vec(d, "y_fit"), Series::Style::dashed, 2});
  // The residuals of each: the model's over the whole record, the step fits' over their steps.
  auto residuals = [&](const char* key, const std::string& panel_title, int color) {
    const auto y = vec(d, "y"), fit = vec(d, key);
    std::vector<double> res(std::min(y.size(), fit.size()));
    for (std::size_t i = 0; i < res.size(); ++i) res[i] = y[i] - fit[i];
    Panel rp{panel_title, "", "residual", false, false, {}, 0.7};
    rp.series.push_back({"", vec(d, "t_s"), res, Series::Style::line, color});
    return rp;
  };
  f.panels = {in, out};
  if (note.empty()) {
    f.panels.push_back(residuals("y_model", "Residuals of the whole-record model", kWholeRecordModelColor));
    f.panels.push_back(residuals("y_fit", "Residuals of the step fits", 3));
    f.height_px = 900;
  } else {
    f.panels.push_back(residuals("y_fit", "Residuals", 3));
    f.panels.back().height_weight = 0.8;
    f.height_px = 760;
  }
  f.panels.back().xlabel = "time (s)";
  f.share_x = true;  // one time axis: the step fits' residuals exist only over their steps
  return f;
}

Figure bode_figure(const nlohmann::json& d) {
  Figure f;
  f.title = "Liquefier frequency response";
  const auto fr = vec(d, "freq_hz");
  Panel mag{"Magnitude", "", "|H| (dB)", true, false, {}, 1.2};
  mag.series.push_back({"measured", fr, vec(d, "mag_db"), Series::Style::points, 1});
  Panel ph{"Phase", "", "phase (deg)", true, false, {}, 1.0};
  ph.series.push_back({"measured", fr, vec(d, "phase_deg"), Series::Style::points, 1});
  if (d.contains("model")) {
    const auto& m = d["model"];
    const std::string label = m.value("label", std::string("fitted model"));
    mag.series.push_back({label, vec(m, "freq_hz"), vec(m, "mag_db"), Series::Style::line, 2});
    ph.series.push_back({label, vec(m, "freq_hz"), vec(m, "phase_deg"), Series::Style::line, 2});
  }
  f.panels = {mag, ph};
  if (d.contains("coherence")) {
    Panel coh{"Coherence", "frequency (Hz)", "coherence", true, false, {}, 0.7};
    coh.series.push_back({"", fr, vec(d, "coherence"), Series::Style::line, 3});
    f.panels.push_back(coh);
  } else {
    f.panels.back().xlabel = "frequency (Hz)";
  }
  f.height_px = 760;
  return f;
}

Figure psd_figure(const nlohmann::json& d, const std::string& axis) {
  Figure f;
  f.title = fmt::format("Axis {}: power spectral density, modes and input shapers", axis);
  const auto fr = vec(d, "freq_hz");
  const auto psd = vec(d, "psd");
  Panel p{"Acceleration PSD", "", "PSD ((mm/s^2)^2/Hz)", false, false, {}, 1.3};
  p.series.push_back({"measured", fr, psd, Series::Style::line, 1});
  double peak = 0;
  for (double v : psd) peak = std::isfinite(v) ? std::max(peak, v) : peak;
  int color = 2;
  if (d.contains("modes"))
    for (const auto& m : d["modes"]) {
      const double fm = m.value("freq_hz", 0.0);
      p.series.push_back({fmt::format("mode {:.1f} Hz", fm), {fm, fm}, {0.0, peak}, Series::Style::dashed, color});
      color = color % 8 + 1;
    }
  Panel s{"Shaper response (remaining vibration)", "frequency (Hz)", "fraction", false, false, {}, 1.0};
  int sc = 2;
  // The recommended shaper is marked: named so in the legend, drawn solid; the others dashed.
  const std::string chosen = d.contains("recommended") ? d["recommended"].value("type", std::string()) : "";
  if (d.contains("shapers"))
    for (const auto& sh : d["shapers"]) {
      const std::string type = sh.value("type", std::string("?"));
      const bool is_chosen = type == chosen;
      s.series.push_back(
          {is_chosen ? fmt::format("{} (recommended, {:.1f} Hz)", type, d["recommended"].value("freq_hz", 0.0)) : type,
           vec(sh, "freq_hz"), vec(sh, "response"),
           is_chosen || chosen.empty() ? Series::Style::line : Series::Style::dashed, sc});
      sc = sc % 8 + 1;
    }
  f.panels = {p};
  if (!s.series.empty()) f.panels.push_back(s);
  else f.panels.back().xlabel = "frequency (Hz)";
  f.height_px = 720;
  return f;
}

Figure viscosity_figure(const nlohmann::json& d) {
  Figure f;
  f.title = "Melt viscosity";
  Panel p{"Viscosity against shear rate", "shear rate (1/s)", "viscosity (Pa s)", true, true, {}, 1.0};
  int c = 1;
  if (d.contains("series"))
    for (const auto& s : d["series"]) {
      const double tk = s.value("temperature_K", 0.0);
      p.series.push_back({fmt::format("{:.0f} K data", tk), vec(s, "shear_rate_1_s"), vec(s, "viscosity_Pa_s"),
                          Series::Style::points, c});
      p.series.push_back({"", vec(s, "fit_shear_rate_1_s"), vec(s, "fit_viscosity_Pa_s"), Series::Style::line, c});
      c = c % 8 + 1;
    }
  f.panels = {p};
  return f;
}

Figure linewidth_figure(const nlohmann::json& d) {
  Figure f;
  f.title = "Line width profile";
  Panel p{"Width along the line", "arc length (mm)", "width (mm)", false, false, {}, 1.0};
  p.series.push_back({"measured", vec(d, "s_mm"), vec(d, "width_mm"), Series::Style::line, 1});
  if (d.contains("setpoint_mm"))
    p.series.push_back({"set point", vec(d, "s_mm"), vec(d, "setpoint_mm"), Series::Style::dashed, 2});
  f.panels = {p};
  f.height_px = 420;
  return f;
}

std::vector<ReportImage> render_report_plots(const std::string& run_dir, const nlohmann::json& pd) {
  std::vector<ReportImage> images;
  const std::string dir = run_dir + "/plots";
  auto add = [&](const std::string& id, const std::string& caption, const Figure& fig) {
    const std::string path = dir + "/" + id + ".svg";
    try {
      render_svg(fig, path);
      images.push_back({id, caption, path, {}});
    } catch (const InputError& e) {
      images.push_back({id, caption, {}, e.message()});  // the report goes on without it
    }
  };
  if (pd.contains("step")) {
    const std::string note = step_model_note(pd["step"]);
    add("step",
        note.empty() ? "Step response: the record, the whole-record model over all of it, each step's fit over its "
                       "step, and the residuals"
                     : "Step response: the record, each step's fit over its step and the residuals; " + note,
        step_figure(pd["step"]));
  }
  if (pd.contains("bode")) add("bode", "Bode plot with the fitted model and the coherence", bode_figure(pd["bode"]));
  for (const char* axis : {"x", "y", "z"}) {
    const std::string key = std::string("psd_") + axis;
    if (pd.contains(key))
      add(key, fmt::format("Axis {}: PSD with identified modes and the candidate shapers' responses", axis),
          psd_figure(pd[key], axis));
  }
  if (pd.contains("overshoot_grid"))
    add("overshoot_grid", "Overshoot, completion time and figure of merit over the speed x acceleration grid",
        overshoot_grid_figure(pd["overshoot_grid"]));
  if (pd.contains("flow_advance"))
    add("flow_advance", "Advance against flow: the need with its 95 % band, each exported model, the design flow",
        flow_advance_figure(pd["flow_advance"]));
  if (pd.contains("viscosity"))
    add("viscosity", "Viscosity against shear rate with the fitted model", viscosity_figure(pd["viscosity"]));
  if (pd.contains("linewidth")) {
    add("linewidth", "Line-width profile", linewidth_figure(pd["linewidth"]));
    // The photo with the detected edges and centreline, shown beside its profile.
    const std::string overlay = pd["linewidth"].value("overlay_png", std::string());
    if (!overlay.empty()) {
      const std::string path = run_dir + "/" + overlay;
      if (!std::filesystem::exists(path))
        throw InputError("the line-width overlay named in plotdata.json is missing", path);
      images.push_back({"linewidth_overlay", "Photo overlay: detected edges and centreline", path, {}});  // a PNG photo
    }
  }
  return images;
}

namespace {

// The "95 % interval" cell of a summary row: [lo, hi] from the row's ci_path, else its basis.
std::string interval_cell(const nlohmann::json& results, const nlohmann::json& row) {
  const std::string ci_path = row.value("ci_path", std::string());
  if (!ci_path.empty()) {
    const auto* ci = json_at(results, ci_path);
    if (ci != nullptr && ci->is_array() && ci->size() == 2 && (*ci)[0].is_number() && (*ci)[1].is_number())
      return fmt::format("<td class=\"ci\" data-path=\"{}\">{}</td>", html::escape(ci_path),
                         display_interval((*ci)[0].get<double>(), (*ci)[1].get<double>()));
    return "<td class=\"ci\">n/a</td>";
  }
  return "<td class=\"ci\">" + html::escape(row.value("basis", std::string("n/a"))) + "</td>";
}

}  // namespace

std::string build_report_html(const nlohmann::json& env, const std::vector<ReportImage>& images) {
  const auto& results = env.contains("results") ? env["results"] : env;
  std::ostringstream h;
  // Nothing may leave the file: no scripts, no fetches; images only from data: URIs.
  h << html::head("tunekit calibration report", report_css(), kReportCsp);
  h << "<h1>tunekit calibration report</h1>\n";
  const std::string machine = results.value("machine", std::string());
  if (!machine.empty()) h << "<p>Machine: " << html::escape(machine) << "</p>\n";
  if (env.contains("tool"))
    h << "<p>tunekit " << html::escape(env["tool"].value("version", std::string("?"))) << ", command <code>"
      << html::escape(env.value("command", std::string("?"))) << "</code></p>\n";

  h << "<h2>Summary</h2>\n<table id=\"summary\">\n"
    << "<tr><th>quantity</th><th>value</th><th>95 % interval</th><th>unit</th></tr>\n";
  if (results.contains("summary"))
    for (const auto& row : results["summary"]) {
      const std::string path = row.value("path", std::string());
      const auto* v = json_at(results, path);
      if (v == nullptr || !v->is_number()) continue;
      h << "<tr><td>" << html::escape(row.value("label", path)) << "</td><td class=\"num\" data-path=\""
        << html::escape(path) << "\" data-value=\"" << v->dump() << "\">" << display_number(v->get<double>()) << "</td>"
        << interval_cell(results, row) << "<td>" << html::escape(row.value("unit", std::string())) << "</td></tr>\n";
    }
  h << "</table>\n";

  if (results.contains("agreement") && results["agreement"].is_array() && !results["agreement"].empty()) {
    h << "<h2>Methods compared</h2>\n";
    for (const auto& a : results["agreement"]) {
      const bool ok = a.value("agree", false);
      h << "<p class=\"" << (ok ? "agree" : "disagree") << "\" id=\"agreement-"
        << html::escape(a.value("id", std::string("quantity"))) << "\" data-agree=\"" << (ok ? "true" : "false")
        << "\">" << html::escape(a.value("statement", std::string())) << "</p>\n";
    }
  }

  if (env.contains("warnings") && !env["warnings"].empty()) {
    h << "<h2>Warnings</h2>\n<ul id=\"warnings\">\n";
    for (const auto& w : env["warnings"]) {
      const std::string text = w.get<std::string>();
      h << "<li class=\"warn\">" << html::escape(text)
        << "<br><span class=\"todo\">What to do: " << html::escape(advice_for_warning(text)) << "</span></li>\n";
    }
    h << "</ul>\n";
  }
  if (results.contains("notes") && results["notes"].is_array() && !results["notes"].empty()) {
    h << "<h2>Notes</h2>\n<ul id=\"notes\">\n";
    for (const auto& n : results["notes"])
      if (n.is_string()) h << "<li>" << html::escape(n.get<std::string>()) << "</li>\n";
    h << "</ul>\n";
  }
  if (!images.empty()) h << "<h2>Plots</h2>\n";
  for (const auto& img : images) {
    if (!img.failure.empty()) {
      h << "<figure id=\"plot-" << img.id << "\"><figcaption>" << html::escape(img.caption) << " ("
        << html::escape(img.failure) << ")</figcaption></figure>\n";
      continue;
    }
    const std::string bytes = read_file_bytes(img.path);
    h << "<figure id=\"plot-" << img.id << "\"><img alt=\"" << html::escape(img.caption)
      << "\" src=\"data:" << image_mime(img.path) << ";base64," << base64(bytes) << "\"><figcaption>"
      << html::escape(img.caption) << "</figcaption></figure>\n";
  }
  if (results.contains("config_diff") && results["config_diff"].is_string() &&
      !results["config_diff"].get<std::string>().empty())
    h << "<h2>Configuration changes</h2>\n<pre>" << html::escape(results["config_diff"].get<std::string>())
      << "</pre>\n";
  h << "</body>\n</html>\n";
  return h.str();
}

}  // namespace tunekit::calibration
