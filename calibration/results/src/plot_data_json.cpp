// plotdata.json: the one writer of the report's typed plot series (plot_data.hpp) and the one
// reader back into them (report.hpp lists the members).
#include <cmath>

#include "tunekit/calibration/results/calibration_record.hpp"

namespace tunekit::calibration {
namespace {

using json = nlohmann::json;

// The numbers of d[key] (NaN for an element that is not a number); empty when d has no array there.
std::vector<double> series(const json& d, const char* key) {
  if (!d.contains(key) || !d[key].is_array()) return {};
  std::vector<double> v;
  v.reserve(d[key].size());
  for (const auto& x : d[key]) v.push_back(x.is_number() ? x.get<double>() : std::nan(""));
  return v;
}

// A column of an array of objects (NaN where a row has no number there).
std::vector<double> column(const json& rows, const char* key) {
  std::vector<double> v;
  for (const auto& r : rows) v.push_back(r.contains(key) && r[key].is_number() ? r[key].get<double>() : std::nan(""));
  return v;
}

json step_json(const StepPlot& p) {
  json d{{"u_label", p.u_label}, {"y_label", p.y_label}, {"t_s", p.t_s}, {"u", p.u}, {"y", p.y}, {"y_fit", p.y_fit}};
  if (p.has_model()) {
    d["model_label"] = p.model_label;
    d["y_model"] = p.y_model;
  } else {
    d["model_missing"] = p.model_missing;
  }
  return d;
}

StepPlot step_from_json(const json& d) {
  StepPlot p;
  p.u_label = d.value("u_label", std::string("input"));
  p.y_label = d.value("y_label", std::string("output"));
  p.t_s = series(d, "t_s");
  p.u = series(d, "u");
  p.y = series(d, "y");
  p.y_fit = series(d, "y_fit");
  p.y_model = series(d, "y_model");
  p.model_label = d.value("model_label", std::string("whole-record model"));
  p.model_missing = d.value("model_missing", std::string());
  return p;
}

json bode_json(const BodePlot& p) {
  json d{{"freq_hz", p.measured.freq_hz}, {"mag_db", p.measured.mag_db}, {"phase_deg", p.measured.phase_deg}};
  if (!p.coherence.empty()) d["coherence"] = p.coherence;
  if (p.model)
    d["model"] = {{"freq_hz", p.model->curve.freq_hz},
                  {"mag_db", p.model->curve.mag_db},
                  {"phase_deg", p.model->curve.phase_deg},
                  {"label", p.model->label}};
  return d;
}

BodePlot bode_from_json(const json& d) {
  BodePlot p;
  p.measured = {series(d, "freq_hz"), series(d, "mag_db"), series(d, "phase_deg")};
  p.coherence = series(d, "coherence");
  if (d.contains("model")) {
    const auto& m = d["model"];
    p.model = BodePlot::Model{{series(m, "freq_hz"), series(m, "mag_db"), series(m, "phase_deg")},
                              m.value("label", std::string("fitted model"))};
  }
  return p;
}

json psd_json(const PsdPlot& p) {
  json d{{"freq_hz", p.freq_hz}, {"psd", p.psd}, {"modes", json::array()}, {"shapers", json::array()}};
  for (double f : p.mode_freq_hz) d["modes"].push_back({{"freq_hz", f}});
  for (const auto& s : p.shapers)
    d["shapers"].push_back({{"type", s.type}, {"freq_hz", s.freq_hz}, {"response", s.response}});
  if (p.recommended) d["recommended"] = {{"type", p.recommended->type}, {"freq_hz", p.recommended->freq_hz}};
  return d;
}

PsdPlot psd_from_json(const json& d) {
  PsdPlot p;
  p.freq_hz = series(d, "freq_hz");
  p.psd = series(d, "psd");
  if (d.contains("modes"))
    for (const auto& m : d["modes"]) p.mode_freq_hz.push_back(m.value("freq_hz", 0.0));
  if (d.contains("shapers"))
    for (const auto& s : d["shapers"])
      p.shapers.push_back({s.value("type", std::string("?")), series(s, "freq_hz"), series(s, "response")});
  if (d.contains("recommended"))
    p.recommended =
        PsdPlot::Recommended{d["recommended"].value("type", std::string()), d["recommended"].value("freq_hz", 0.0)};
  return p;
}

json flow_advance_json(const FlowAdvancePlot& p) {
  json curve = json::array();
  for (std::size_t i = 0; i < p.flow_mm3_s.size(); ++i)
    curve.push_back({{"flow_mm3_s", p.flow_mm3_s[i]},
                     {"tau_s", p.tau_s[i]},
                     {"K_need_s", p.k_need_s[i]},
                     {"K_lo_s", p.k_lo_s[i]},
                     {"K_hi_s", p.k_hi_s[i]},
                     {"K_kalico_s", p.k_kalico_s[i]}});
  json orca = json::array();
  for (std::size_t i = 0; i < p.orca_flow_mm3_s.size(); ++i)
    orca.push_back({{"flow_mm3_s", p.orca_flow_mm3_s[i]}, {"K_s", p.orca_k_s[i]}});
  json d{{"curve", curve},
         {"orca", orca},
         {"single", {{"K_s", p.k_single_s}}},
         {"design_flow_mm3_s", p.design_flow_mm3_s}};
  if (!p.kalico_model.empty()) d["kalico"] = {{"pressure_advance_model", p.kalico_model}};
  if (p.rheology)
    d["rheology"] = {{"flow_mm3_s", p.rheology->flow_mm3_s},
                     {"tau_pred_s", p.rheology->tau_pred_s},
                     {"max_gap_rel", p.rheology->max_gap_rel}};
  return d;
}

json linewidth_json(const LinewidthPlot& p) {
  json d{{"s_mm", p.s_mm}, {"width_mm", p.width_mm}, {"setpoint_mm", p.setpoint_mm}};
  if (!p.overlay_png.empty()) d["overlay_png"] = p.overlay_png;
  return d;
}

LinewidthPlot linewidth_from_json(const json& d) {
  return {series(d, "s_mm"), series(d, "width_mm"), series(d, "setpoint_mm"), d.value("overlay_png", std::string())};
}

json overshoot_grid_json(const OvershootGridPlot& p) {
  json cells = json::array();
  for (const auto& c : p.cells)
    cells.push_back({{"input_shaping", c.input_shaping},
                     {"speed_mm_s", c.speed_mm_s},
                     {"accel_mm_s2", c.accel_mm_s2},
                     {"overshoot_mm", c.overshoot_mm},
                     {"completion_time_s", c.completion_time_s},
                     {"figure_of_merit", c.figure_of_merit}});
  return {{"tolerance_mm", p.tolerance_mm}, {"cells", cells}};
}

OvershootGridPlot overshoot_grid_from_json(const json& d) {
  OvershootGridPlot p;
  p.tolerance_mm = d.value("tolerance_mm", 0.0);
  if (d.contains("cells"))
    for (const auto& c : d["cells"])
      p.cells.push_back({c.value("input_shaping", false), c.value("speed_mm_s", 0.0), c.value("accel_mm_s2", 0.0),
                         c.value("overshoot_mm", 0.0), c.value("completion_time_s", 0.0),
                         c.value("figure_of_merit", 0.0)});
  return p;
}

json viscosity_json(const ViscosityPlot& p) {
  json list = json::array();
  for (const auto& s : p.series)
    list.push_back({{"temperature_K", s.temperature_K},
                    {"shear_rate_1_s", s.shear_rate_1_s},
                    {"viscosity_Pa_s", s.viscosity_Pa_s},
                    {"fit_shear_rate_1_s", s.fit_shear_rate_1_s},
                    {"fit_viscosity_Pa_s", s.fit_viscosity_Pa_s}});
  return {{"series", list}};
}

ViscosityPlot viscosity_from_json(const json& d) {
  ViscosityPlot p;
  if (d.contains("series"))
    for (const auto& s : d["series"])
      p.series.push_back({s.value("temperature_K", 0.0), series(s, "shear_rate_1_s"), series(s, "viscosity_Pa_s"),
                          series(s, "fit_shear_rate_1_s"), series(s, "fit_viscosity_Pa_s")});
  return p;
}

}  // namespace

json plotdata_json(const ReportPlots& plots) {
  json pd = json::object();
  if (plots.step) pd["step"] = step_json(*plots.step);
  if (plots.bode) pd["bode"] = bode_json(*plots.bode);
  for (const auto& [axis, p] : plots.psd) pd["psd_" + axis] = psd_json(p);
  if (plots.overshoot_grid) pd["overshoot_grid"] = overshoot_grid_json(*plots.overshoot_grid);
  if (plots.flow_advance) pd["flow_advance"] = flow_advance_json(*plots.flow_advance);
  if (plots.viscosity) pd["viscosity"] = viscosity_json(*plots.viscosity);
  if (plots.linewidth) pd["linewidth"] = linewidth_json(*plots.linewidth);
  if (plots.thermal) pd["thermal"] = step_json(*plots.thermal);
  return pd;
}

ReportPlots plots_from_json(const json& pd) {
  ReportPlots plots;
  if (!pd.is_object()) return plots;
  if (pd.contains("step")) plots.step = step_from_json(pd["step"]);
  if (pd.contains("thermal")) plots.thermal = step_from_json(pd["thermal"]);
  if (pd.contains("bode")) plots.bode = bode_from_json(pd["bode"]);
  for (const char* axis : {"x", "y", "z"})
    if (pd.contains(std::string("psd_") + axis)) plots.psd[axis] = psd_from_json(pd[std::string("psd_") + axis]);
  if (pd.contains("overshoot_grid")) plots.overshoot_grid = overshoot_grid_from_json(pd["overshoot_grid"]);
  if (pd.contains("flow_advance")) plots.flow_advance = flow_advance_plot_from_json(pd["flow_advance"]);
  if (pd.contains("viscosity")) plots.viscosity = viscosity_from_json(pd["viscosity"]);
  if (pd.contains("linewidth")) plots.linewidth = linewidth_from_json(pd["linewidth"]);
  return plots;
}

FlowAdvancePlot flow_advance_plot_from_json(const json& fa) {
  FlowAdvancePlot p;
  const auto& curve = fa.at("curve");
  p.flow_mm3_s = column(curve, "flow_mm3_s");
  p.tau_s = column(curve, "tau_s");
  p.k_need_s = column(curve, "K_need_s");
  p.k_lo_s = column(curve, "K_lo_s");
  p.k_hi_s = column(curve, "K_hi_s");
  p.k_kalico_s = column(curve, "K_kalico_s");
  if (fa.contains("kalico")) p.kalico_model = fa["kalico"].value("pressure_advance_model", std::string("?"));
  if (fa.contains("single") && fa["single"].contains("K_s") && fa["single"]["K_s"].is_number())
    p.k_single_s = fa["single"]["K_s"].get<double>();
  if (fa.contains("design_flow_mm3_s") && fa["design_flow_mm3_s"].is_number())
    p.design_flow_mm3_s = fa["design_flow_mm3_s"].get<double>();
  if (fa.contains("orca") && fa["orca"].is_array()) {
    p.orca_flow_mm3_s = column(fa["orca"], "flow_mm3_s");
    p.orca_k_s = column(fa["orca"], "K_s");
  }
  if (fa.contains("rheology") && fa["rheology"].is_object()) p.rheology = flow_rheology_from_json(fa["rheology"]);
  return p;
}

FlowAdvancePlot::Rheology flow_rheology_from_json(const json& r) {
  FlowAdvancePlot::Rheology rh;
  if (r.contains("flow_mm3_s") && r.contains("tau_pred_s")) {
    rh.flow_mm3_s = r["flow_mm3_s"].get<std::vector<double>>();
    rh.tau_pred_s = r["tau_pred_s"].get<std::vector<double>>();
  }
  if (r.contains("max_gap_rel") && r["max_gap_rel"].is_number()) rh.max_gap_rel = r["max_gap_rel"].get<double>();
  return rh;
}

}  // namespace tunekit::calibration
