// The inputs of the compensator design (design_inputs.hpp): from the analyses' typed outcomes,
// and from the results files a user names, one reader per kind of result. This is the only
// place export reads results JSON.
#include "tunekit/calibration/commands/design_inputs.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/results/json_access.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"

namespace tunekit::calibration {
namespace {

using nlohmann::json;

/// A number of a results file, NaN when absent (null); InputError when it is not a number.
double number_at(const json& root, const char* pointer, const std::string& what, const std::string& path) {
  const json& j = value_at_or_null(root, json::json_pointer(pointer));
  if (j.is_null()) return fitting::kNaN;
  if (!j.is_number()) throw InputError(fmt::format("{} must be a number", what), path);
  return j.get<double>();
}

/// {value, stderr, ci95: [lo, hi]} of a fitted parameter in a results file.
EstimatedValue estimated_at(const json& param, const std::string& what, const std::string& path) {
  EstimatedValue e;
  e.value = number_at(param, "/value", what + ".value", path);
  e.std_error = number_at(param, "/stderr", what + ".stderr", path);
  const json& ci = value_at_or_null(param, "/ci95"_json_pointer);
  if (ci.is_array() && ci.size() == 2 && ci[0].is_number() && ci[1].is_number()) {
    e.ci95_lo = ci[0].get<double>();
    e.ci95_hi = ci[1].get<double>();
  }
  return e;
}

/// A fitted parameter of a results file, checked before anything is designed from it: a value
/// that is given must be finite (and above 0 when `positive`: a time constant, a gain), and its
/// 95 % interval, when given, finite and wider than zero (a fit gives every estimate an
/// uncertainty). A compensator is only ever turned off by an option (--no-pa, --pa-k 0), never
/// by a results file of zeros.
EstimatedValue fitted_at(const json& param, const std::string& what, const std::string& path, bool positive = true) {
  const EstimatedValue e = estimated_at(param, what, path);
  const bool given = !value_at_or_null(param, "/value"_json_pointer).is_null();
  if (given && (!std::isfinite(e.value) || (positive && !(e.value > 0))))
    throw InputError(fmt::format("{}.value is {}: a fitted {} must be {}; refused before designing anything", what,
                                 e.value, what, positive ? "finite and above 0" : "finite"),
                     path);
  const bool has_interval = value_at_or_null(param, "/ci95"_json_pointer).is_array();
  if (given && has_interval && !(std::isfinite(e.ci95_lo) && std::isfinite(e.ci95_hi) && e.ci95_hi > e.ci95_lo))
    throw InputError(fmt::format("{}.ci95 [{}, {}] is not a 95 % interval of non-zero width: not the result of a "
                                 "fit; refused before designing anything",
                                 what, e.ci95_lo, e.ci95_hi),
                     path);
  return e;
}

/// An operating point's time constant: absent, or finite and above 0 with an interval of non-zero width.
void check_level_tau(const StepLevel& l, const std::string& path) {
  if (std::isnan(l.tau_s) && std::isnan(l.tau_ci95_lo) && std::isnan(l.tau_ci95_hi)) return;
  if (!(std::isfinite(l.tau_s) && l.tau_s > 0) ||
      ((std::isfinite(l.tau_ci95_lo) || std::isfinite(l.tau_ci95_hi)) && !(l.tau_ci95_hi > l.tau_ci95_lo)))
    throw InputError(fmt::format("operating_points[].tau_s {} s [{}, {}] is not a fitted time constant (finite, above "
                                 "0, with an interval of non-zero width); refused before designing anything",
                                 l.tau_s, l.tau_ci95_lo, l.tau_ci95_hi),
                     path);
}

EstimatedValue estimated_of(const fitting::Param& p) { return {p.value, p.std_error, p.ci95_lo, p.ci95_hi}; }

/// Whether the step analysis' operating points are levels of the extruder's feed (mm/s) or of
/// the volumetric flow (mm^3/s), what the flow-dependent advance is designed over. A log whose
/// input is something else (the set-point width of a printed line, in mm) has levels the design
/// cannot place on the flow axis: its pooled fit is designed from. An unstated unit ("1") is
/// taken as a feed, as export has always read it.
/// The whole-record model designs the advance only when the record's own step fits do not
/// contradict it (ident::step_checks_contradict_model, the rule the step analysis warns by):
/// otherwise the store does not describe this liquefier well enough and the operating points
/// design instead.
bool model_agrees_with_steps(std::size_t checks, std::size_t disagreeing) {
  return !ident::step_checks_contradict_model(checks, disagreeing);
}

bool levels_are_feed_or_flow(const std::string& input_unit) {
  return input_unit.empty() || input_unit == "1" || input_unit == "mm/s" ||
         formats::is_volumetric_flow_unit(input_unit);
}

/// The whole-record model's stored-volume fields: the sensor, V's relative width, the rest volume.
void read_volume_fields(const json& res, const std::string& path, StepModelInput& m) {
  m.sensor_reads_volume = value_at_or_null(res, "/whole_record/sensor"_json_pointer) == json("pressure");
  m.u_ref = number_at(res, "/whole_record/reference_input", "whole_record.reference_input", path);
  const std::string cov = "/whole_record/ln_tau_ref_b_covariance/";
  auto cov_at = [&](const std::string& name) {
    return number_at(res, (cov + name).c_str(), "whole_record.ln_tau_ref_b_covariance." + name, path);
  };
  m.ln_tau_b_cov = {cov_at("var_ln_tau_ref"), cov_at("cov_ln_tau_ref_b"), cov_at("var_b")};
  if (m.ln_tau_b_cov[0] < 0 || m.ln_tau_b_cov[2] < 0)
    throw InputError("whole_record.ln_tau_ref_b_covariance: a variance must not be negative", path);
  m.volume_rel_ci95 =
      number_at(res, "/whole_record/volume_rel_ci95_over_range", "whole_record.volume_rel_ci95_over_range", path);
  if (value_at_or_null(res, "/whole_record/rest_volume/measured"_json_pointer) != json(true)) return;
  StepModelInput::RestVolume v;
  v.u = number_at(res, "/whole_record/rest_volume/input", "whole_record.rest_volume.input", path);
  v.value = number_at(res, "/whole_record/rest_volume/value", "whole_record.rest_volume.value", path);
  v.ci95_lo = number_at(res, "/whole_record/rest_volume/ci95/0", "whole_record.rest_volume.ci95[0]", path);
  v.ci95_hi = number_at(res, "/whole_record/rest_volume/ci95/1", "whole_record.rest_volume.ci95[1]", path);
  if (!(v.u > 0 && v.value > 0 && v.ci95_lo <= v.value && v.value <= v.ci95_hi && std::isfinite(v.ci95_hi)))
    throw InputError(fmt::format("whole_record.rest_volume: a measured volume needs a positive input and value inside "
                                 "its 95 % interval (input {}, value {}, ci95 [{}, {}])",
                                 v.u, v.value, v.ci95_lo, v.ci95_hi),
                     path);
  m.rest_volume = v;
}

StepDesignInput read_step_results(const json& res, const std::string& path) {
  StepDesignInput in;
  in.origin = path;
  const json& params = value_at_or_null(res, "/pooled/params"_json_pointer);
  if (params.is_object()) {
    in.tau_s = fitted_at(value_at_or_null(params, "/tau_s"_json_pointer), "pooled.params.tau_s", path, true);
    in.theta_s = estimated_at(value_at_or_null(params, "/theta_s"_json_pointer), "pooled.params.theta_s", path);
    in.K = fitted_at(value_at_or_null(params, "/K"_json_pointer), "pooled.params.K", path, true);
    if (const json& unit = value_at_or_null(params, "/K/unit"_json_pointer); unit.is_string())
      in.K_unit = unit.get<std::string>();
  }
  if (const json& wr = value_at_or_null(res, "/whole_record/a"_json_pointer); wr.is_object()) {
    StepModelInput m;
    m.a = fitted_at(wr, "whole_record.a", path, true);
    m.b = estimated_at(value_at_or_null(res, "/whole_record/b"_json_pointer), "whole_record.b", path);
    m.theta_s = estimated_at(value_at_or_null(res, "/whole_record/theta_s"_json_pointer), "whole_record.theta_s", path);
    m.linear = value_at_or_null(res, "/whole_record/linear_chosen"_json_pointer) == json(true);
    m.u_min = number_at(res, "/whole_record/input_range/0", "whole_record.input_range[0]", path);
    m.u_max = number_at(res, "/whole_record/input_range/1", "whole_record.input_range[1]", path);
    m.tau_rel_ci95 =
        number_at(res, "/whole_record/tau_rel_ci95_over_range", "whole_record.tau_rel_ci95_over_range", path);
    read_volume_fields(res, path, m);
    std::size_t checks = 0, disagreeing = 0;
    if (const json& sc = value_at_or_null(res, "/whole_record/step_checks"_json_pointer); sc.is_array())
      for (const json& c : sc) {
        ++checks;
        disagreeing += value_at_or_null(c, "/disagrees"_json_pointer) == json(true);
      }
    if (std::isfinite(m.a.value) && std::isfinite(m.b.value) && model_agrees_with_steps(checks, disagreeing))
      in.model = m;
  }
  const double a = number_at(res, "/trend/tau_s/a", "trend.tau_s.a", path);
  const double b = number_at(res, "/trend/tau_s/b", "trend.tau_s.b", path);
  if (std::isfinite(a) && std::isfinite(b)) in.trend = design::TauPowerLaw{a, b};
  in.trend_b_ci95_lo = number_at(res, "/trend/tau_s/b_ci95/0", "trend.tau_s.b_ci95[0]", path);
  in.trend_b_ci95_hi = number_at(res, "/trend/tau_s/b_ci95/1", "trend.tau_s.b_ci95[1]", path);
  const json& unit = value_at_or_null(res, "/units/input"_json_pointer);
  const std::string input_unit = unit.is_string() ? unit.get<std::string>() : std::string();
  in.levels_in_flow = formats::is_volumetric_flow_unit(input_unit);
  const json& ops = value_at_or_null(res, "/operating_points"_json_pointer);
  if (!levels_are_feed_or_flow(input_unit)) in.model.reset();
  if (!ops.is_array() || !levels_are_feed_or_flow(input_unit)) {
    in.trend.reset();
    return in;
  }
  for (const json& op : ops) {
    StepLevel l;
    l.u = number_at(op, "/u", "operating_points[].u", path);
    if (!(l.u > 0)) continue;  // arrivals at a stop: no flow to design for
    l.K = number_at(op, "/K", "operating_points[].K", path);
    l.tau_s = number_at(op, "/tau_s", "operating_points[].tau_s", path);
    l.theta_s = number_at(op, "/theta_s", "operating_points[].theta_s", path);
    l.flow_mm3_s = number_at(op, "/flow_mm3_s", "operating_points[].flow_mm3_s", path);
    l.tau_ci95_lo = number_at(op, "/tau_ci95/0", "operating_points[].tau_ci95[0]", path);
    l.tau_ci95_hi = number_at(op, "/tau_ci95/1", "operating_points[].tau_ci95[1]", path);
    check_level_tau(l, path);
    in.levels.push_back(l);
  }
  return in;
}

FreqDesignInput read_freq_results(const json& res, const std::string& path) {
  // The fit freq reports as its result (results.fit), as its report and the history do.
  FreqDesignInput in;
  in.origin = path;
  in.tau_s = fitted_at(value_at_or_null(res, "/fit/params/tau_s"_json_pointer), "fit.params.tau_s", path, true);
  in.input_min = number_at(res, "/input_range/min", "input_range.min", path);
  in.input_max = number_at(res, "/input_range/max", "input_range.max", path);
  in.input_mean = number_at(res, "/input_range/mean", "input_range.mean", path);
  return in;
}

firmware::ShaperSetting shaper_setting_at(const json& c, const std::string& what, const std::string& path) {
  firmware::ShaperSetting s;
  const json& type = value_at_or_null(c, "/type"_json_pointer);
  if (!type.is_string()) throw InputError(fmt::format("{}.type must be a string", what), path);
  s.type = type.get<std::string>();
  s.freq_hz = number_at(c, "/freq_hz", what + ".freq_hz", path);
  if (!std::isnan(s.freq_hz) && !(std::isfinite(s.freq_hz) && s.freq_hz > 0))
    throw InputError(fmt::format("{}.freq_hz is {}: a shaper frequency must be finite and above 0", what, s.freq_hz),
                     path);
  const double z = number_at(c, "/damping", what + ".damping", path);
  if (std::isfinite(z)) s.damping = z;
  return s;
}

void read_shaper_results(const json& res, const std::string& path, DesignInputs& out) {
  const json& axes = value_at_or_null(res, "/axes"_json_pointer);
  if (!axes.is_object()) throw InputError("shaper results without 'axes'", path);
  for (const auto& item : axes.items()) {
    const std::string axis = item.key();
    const json& v = item.value();
    const json& rec = value_at_or_null(v, "/recommended"_json_pointer);
    if (!rec.is_object()) continue;
    if (axis != "x" && axis != "y" && axis != "z") {
      out.unnamed_axes.push_back(
          fmt::format("{}: the shaper of '{}' is not exported: that record names no axis; "
                      "run 'tunekit shaper' on it with --axis x, --axis y or --axis z",
                      path, axis));
      out.warnings.push_back(out.unnamed_axes.back());
      continue;
    }
    AxisShaperInput a;
    a.origin = path;
    a.recommended = shaper_setting_at(rec, "axes." + axis + ".recommended", path);
    const json& cands = value_at_or_null(v, "/candidates"_json_pointer);
    if (cands.is_array())
      for (const json& c : cands)
        a.candidates.push_back({shaper_setting_at(c, "axes." + axis + ".candidates[]", path),
                                number_at(c, "/score", "candidates[].score", path)});
    out.axes[axis] = a;
  }
}

RheoDesignInput read_rheo_results(const json& res, const std::string& path) {
  const json& pred = value_at_or_null(res, "/prediction"_json_pointer);
  if (!pred.is_object())
    throw InputError(
        "rheo results without 'prediction': run 'tunekit rheo' with the nozzle (--nozzle-d, and --nozzle-l) so that "
        "it predicts how tau changes over the flow, and export it beside the results of 'tunekit step' or 'freq'",
        path);
  RheoDesignInput in;
  in.origin = path;
  try {
    in.flow_mm3_s = pred.at("flow_mm3_s").get<std::vector<double>>();
    in.relative_tau = pred.at("relative_tau").get<std::vector<double>>();
  } catch (const json::exception&) {
    throw InputError("prediction.flow_mm3_s and prediction.relative_tau must be arrays of numbers", path);
  }
  in.reference_flow_mm3_s = number_at(pred, "/reference_flow_mm3_s", "prediction.reference_flow_mm3_s", path);
  return in;
}

/// One model value: a number, or a fitted parameter whose value is taken; required.
double thermal_value(const json& model, const char* key, const std::string& path, bool required = true) {
  const json& j = value_at_or_null(model, json::json_pointer(std::string("/") + key));
  const json& v = j.is_object() ? value_at_or_null(j, "/value"_json_pointer) : j;
  if (v.is_null() && !required) return 0.0;
  if (!v.is_number())
    throw InputError(fmt::format("results.thermal_model.{} must be a number (or {{\"value\": number}})", key), path);
  return v.get<double>();
}

ThermalDesignInput read_thermal_results(const json& res, const std::string& path) {
  // `tunekit thermal` writes results.thermal_model (calibration/analyses thermal_command.cpp).
  const json& tm = value_at_or_null(res, "/thermal_model"_json_pointer);
  const json& m = tm.is_object() ? tm : value_at_or_null(res, "/model"_json_pointer);
  if (!m.is_object()) throw InputError("thermal results without a 'thermal_model' object", path);
  ThermalDesignInput in;
  in.origin = path;
  auto& t = in.model;
  t.heater_power_w = thermal_value(m, "heater_power_w", path);
  t.block_heat_capacity_j_per_k = thermal_value(m, "block_heat_capacity_j_per_k", path);
  t.sensor_responsiveness_per_s = thermal_value(m, "sensor_responsiveness_per_s", path);
  t.ambient_transfer_w_per_k = thermal_value(m, "ambient_transfer_w_per_k", path);
  t.fan_transfer_w_per_k = thermal_value(m, "fan_transfer_w_per_k", path);
  t.filament_heat_capacity_j_per_k_mm = thermal_value(m, "filament_heat_capacity_j_per_k_mm", path, false);
  t.ambient_c =
      value_at_or_null(m, "/ambient_c"_json_pointer).is_null() ? t.ambient_c : thermal_value(m, "ambient_c", path);
  return in;
}

void read_one_results_file(const std::string& path, DesignInputs& out) {
  std::string bytes;
  const json j = read_results_json(path, &bytes);
  out.files.push_back(input_digest(path, bytes));
  out.origins.push_back(path);
  const std::string cmd = j.value("command", std::string());
  const json& res = value_at_or_null(j, "/results"_json_pointer);
  if (!res.is_object()) throw InputError("no 'results' object: not a tunekit results file", path);
  if (cmd == "step") out.step = read_step_results(res, path);
  else if (cmd == "freq") out.freq = read_freq_results(res, path);
  else if (cmd == "shaper") read_shaper_results(res, path, out);
  else if (cmd == "rheo") out.rheo = read_rheo_results(res, path);
  else if (cmd == "thermal") out.thermal = read_thermal_results(res, path);
  else
    throw InputError(fmt::format("results of '{}' cannot be exported (step, freq, shaper, rheo or thermal)", cmd),
                     path);
}

}  // namespace

DesignInputs read_design_inputs(const std::vector<std::string>& results_files) {
  DesignInputs out;
  for (const auto& path : results_files) {
    try {
      read_one_results_file(path, out);
    } catch (const json::exception& e) {
      throw InputError(fmt::format("unexpected content in a results file: {}", core::plain_json_error(e.what())), path);
    }
  }
  return out;
}

StepDesignInput step_design_input(const StepOutcome& o, const std::string& origin) {
  StepDesignInput in;
  in.origin = origin;
  const ident::StepAnalysis& a = o.analysis;
  if (a.pooled) {
    in.tau_s = estimated_of(a.pooled->param("tau_s"));
    in.theta_s = estimated_of(a.pooled->param("theta_s"));
    in.K = estimated_of(a.pooled->param("K"));
    in.K_unit = a.pooled->param("K").unit;
  }
  in.levels_in_flow = formats::is_volumetric_flow_unit(o.input_unit);
  if (const auto& wr = o.whole_record.model) {
    const auto& f = wr->model.fit;
    StepModelInput m;
    m.a = estimated_of(f.derived.front());
    m.b = estimated_of(f.param("b"));
    m.theta_s = estimated_of(f.param("theta_s"));
    m.linear = wr->model.linear_chosen;
    m.u_min = wr->input_min_positive;
    m.u_max = wr->input_max;
    m.tau_rel_ci95 = wr->tau_relative_half_width_over_range();
    m.sensor_reads_volume = wr->model.sensor == fitting::LiquefierSensor::pressure;
    m.u_ref = wr->model.reference_input;
    m.ln_tau_b_cov = wr->ln_tau_ref_b_covariance();
    m.volume_rel_ci95 = wr->volume_relative_half_width_over_range();
    if (const auto& rv = wr->rest_volume)
      m.rest_volume = StepModelInput::RestVolume{rv->input, rv->value, rv->ci95_lo, rv->ci95_hi};
    if (!ident::step_checks_contradict_model(wr->checks)) in.model = m;
  }
  if (!levels_are_feed_or_flow(o.input_unit)) {
    in.model.reset();
    return in;
  }
  if (a.level_trends.tau) {
    const auto& b = a.level_trends.tau->param("b");
    in.trend = design::TauPowerLaw{a.level_trends.tau->value("a"), b.value};
    in.trend_b_ci95_lo = b.ci95_lo;
    in.trend_b_ci95_hi = b.ci95_hi;
  }
  for (const auto& l : a.arrival_levels) {
    if (!(l.u > 0)) continue;
    const auto& tau = l.fit.param("tau_s");
    in.levels.push_back(
        {l.u, l.fit.value("K"), tau.value, l.fit.value("theta_s"), tau.ci95_lo, tau.ci95_hi, fitting::kNaN});
  }
  return in;
}

FreqDesignInput freq_design_input(const FreqOutcome& o, const std::string& origin) {
  FreqDesignInput in;
  in.origin = origin;
  if (const fitting::FitResult* fit = o.reported_fit()) in.tau_s = estimated_of(fit->param("tau_s"));
  in.input_min = o.input_min;
  in.input_max = o.input_max;
  in.input_mean = o.input_mean;
  return in;
}

bool step_tau_for_freq(const StepDesignInput& s, const FreqDesignInput& f, Estimate& out) {
  const bool flow_dependent = s.trend && (s.trend_b_ci95_lo > 0 || s.trend_b_ci95_hi < 0);
  const double lo = std::max(f.input_min, 0.0), hi = f.input_max, mean = f.input_mean;
  if (flow_dependent && lo > 0 && hi > lo && mean > 0) {
    auto tau = [&](double u) { return s.trend->a * std::pow(u, s.trend->b); };
    out = {fmt::format("step-response trend over the frequency record's inputs {:.4g}-{:.4g}", lo, hi), tau(mean),
           std::min({tau(lo), tau(hi), tau(mean)}), std::max({tau(lo), tau(hi), tau(mean)})};
  } else {
    out = {"step response", s.tau_s.value, s.tau_s.ci95_lo, s.tau_s.ci95_hi};
  }
  return std::isfinite(out.value) && std::isfinite(out.ci95_lo) && std::isfinite(out.ci95_hi);
}

std::map<std::string, AxisShaperInput> shaper_design_inputs(const ShaperOutcome& o, const std::string& origin) {
  std::map<std::string, AxisShaperInput> out;
  for (const auto& x : o.axes) {
    const std::string& label = x.resonance.label;
    if (label != "x" && label != "y") continue;
    auto setting = [](const design::ShaperCandidate& c) {
      return firmware::ShaperSetting{design::to_string(c.type), c.freq_hz, c.damping_ratio};
    };
    AxisShaperInput a;
    a.origin = origin;
    a.recommended = setting(x.choice.recommended);
    for (const auto& c : x.choice.candidates) a.candidates.push_back({setting(c), c.score});
    out[label] = a;
  }
  return out;
}

}  // namespace tunekit::calibration
