// tunekit nozzle: the pressure drop of a melt through a nozzle (Hagen-Poiseuille, power-law
// capillary with the Rabinowitsch correction, Bellini's three-zone model, Boles' model) from
// rheology and geometry, and the inverse fit of K and n from measured flow and pressure (or
// feeder force) at known temperature, as in the load-cell experiments of Holtrup 2019 sec. 5.3.
#include <cmath>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/calibration/analyses/nozzle_command.hpp"
#include "tunekit/calibration/results/row_limit.hpp"
#include "tunekit/core/json_error_text.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {

double nozzle_display_value(double si, double per_si) { return std::stod(fmt::format("{:.12g}", si * per_si)); }

namespace {

constexpr double kNozzleRadPerDeg = std::numbers::pi / 180.0;

nlohmann::json nozzle_geometry_json(const fitting::NozzleGeometry& g) {
  return {{"d_mm", nozzle_display_value(g.d_m, 1e3)},
          {"l_mm", nozzle_display_value(g.l_m, 1e3)},
          {"cone_half_angle_deg", nozzle_display_value(g.cone_half_angle_rad, 1 / kNozzleRadPerDeg)},
          {"D_mm", nozzle_display_value(g.D_m, 1e3)},
          {"melt_length_mm", nozzle_display_value(g.melt_length_m, 1e3)}};
}

NozzleFit compute_nozzle_fit(const NozzleOptions& a, NozzleOutcome& outcome) {
  const std::string bytes = read_file_bytes(a.fit_file);
  outcome.input_path = a.fit_file;
  outcome.input_sha256 = sha256_hex(bytes);
  outcome.input_size_bytes = bytes.size();
  require_line_limit(bytes, a.max_rows, "--max-rows", a.fit_file);
  const auto t = formats::parse_csv(bytes, a.fit_file);
  require_row_limit(t.rows, a.max_rows, "--max-rows", a.fit_file);
  const auto hdr = source_location(a.fit_file, t.header_line);
  if (!t.has_column("flow")) throw InputError("no 'flow (mm3/s)' column", hdr);
  const auto& fc = t.column("flow");
  double ff = 1e-9;
  if (fc.unit == "m3/s") ff = 1.0;
  else if (!(fc.unit.empty() || fc.unit == "mm3/s" || fc.unit == "mm^3/s"))
    throw InputError("flow unit '" + fc.unit + "' (use mm3/s or m3/s)", hdr);
  fitting::NozzleFlowData d;
  std::vector<double> p;
  if (t.has_column("pressure")) {
    const auto& pc = t.column("pressure");
    const double pf = formats::pressure_unit_factor(pc.unit);
    for (double v : pc.values) p.push_back(v * pf);
  } else if (t.has_column("force")) {
    const auto& fcol = t.column("force");
    if (!(fcol.unit.empty() || fcol.unit == "N")) throw InputError("force unit '" + fcol.unit + "' (use N)", hdr);
    if (!(a.piston_diameter_mm > 0))
      throw InputError("a force column needs --piston-diameter (mm) to turn the force into a pressure (P = F / A)");
    const double area = std::numbers::pi / 4 * std::pow(a.piston_diameter_mm * 1e-3, 2);
    for (double v : fcol.values) p.push_back(v / area);
  } else {
    throw InputError("no 'pressure (MPa)' or 'force (N)' column", hdr);
  }
  std::vector<double> T;
  if (t.has_column("temperature")) {
    const auto& tc = t.column("temperature");
    for (double v : tc.values) {
      if (tc.unit == "K") {
        if (v < 273.15)
          throw InputError(fmt::format("temperature {:g} K is below 0 degC; the values look like degC", v), hdr);
        T.push_back(v);
      } else if (tc.unit == "degC" || tc.unit == "C") {
        if (v > 600)
          throw InputError(fmt::format("temperature {:g} degC is above 600 degC; the values look like kelvin", v), hdr);
        T.push_back(v + a.kelvin_offset);
      } else {
        throw InputError("the temperature column needs a unit: 'temperature (degC)' or '(K)'", hdr);
      }
    }
  } else if (std::isfinite(a.temperature_degc)) {
    T.assign(t.rows, a.temperature_degc + a.kelvin_offset);
  } else {
    throw InputError("no temperature: add a 'temperature (degC)' column or give --temperature (degC)");
  }
  for (std::size_t i = 0; i < t.rows; ++i) {
    d.flow_m3_s.push_back(fc.values[i] * ff);
    d.pressure_Pa.push_back(p[i]);
    d.temperature_K.push_back(T[i]);
  }
  fitting::validate(a.prediction.geometry);
  NozzleFit out;
  out.rows = t.rows;
  out.fit = fitting::fit_nozzle_rheology(d, a.prediction.model, a.prediction.geometry);
  outcome.warnings.insert(outcome.warnings.end(), out.fit.warnings.begin(), out.fit.warnings.end());
  return out;
}

/// Refuses a fit that lacks a parameter its model evaluates (the evaluation would fail on it).
void require_rheology_params(const fitting::ViscositySpec& spec, const std::string& path) {
  auto names = fitting::viscosity_param_names(spec.model);
  for (const auto& n : fitting::shift_param_names(spec.shift)) names.push_back(n);
  std::string all;
  for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
  for (const auto& n : names)
    if (!spec.values.count(n))
      throw InputError(
          fmt::format("the rheology fit has no parameter '{}' (its model {} needs {})", n, spec.name(), all), path);
}

NozzleForward compute_nozzle_forward(const NozzleOptions& a, NozzleOutcome& outcome) {
  const fitting::NozzleGeometry& g = a.prediction.geometry;
  fitting::validate(g);
  const auto model = a.prediction.model;
  const int sources = (std::isfinite(a.K) || std::isfinite(a.n) ? 1 : 0) + (std::isfinite(a.mu) ? 1 : 0) +
                      (a.material.empty() ? 0 : 1) + (a.rheology_json.empty() ? 0 : 1);
  if (sources != 1)
    throw InputError("give the rheology one way: --K and --n, --mu, --material NAME, or --rheology FIT.json");
  if (a.flows_mm3_s.empty()) throw InputError("give at least one --flow (mm3/s)");
  NozzleForward out;
  const double T_K = std::isfinite(a.temperature_degc) ? a.temperature_degc + a.kelvin_offset : fitting::kNaN;

  // Every source becomes a viscosity function of shear rate and temperature.
  fitting::ViscositySpec spec;
  std::string& source = out.rheology;
  if (std::isfinite(a.K) || std::isfinite(a.n)) {
    if (!(a.K > 0) || !(a.n > 0 && a.n <= 1.5)) throw InputError("--K (Pa.s^n) must be > 0 and --n in (0, 1.5]");
    spec.model = fitting::ViscosityModel::power_law;
    spec.values = {{"K_Pa_s_n", a.K}, {"n", a.n}};
    source = fmt::format("power law K {:g} Pa.s^n, n {:g}", a.K, a.n);
  } else if (std::isfinite(a.mu)) {
    if (!(a.mu > 0)) throw InputError("--mu (Pa.s) must be positive");
    spec.model = fitting::ViscosityModel::newtonian;
    spec.values = {{"eta0_Pa_s", a.mu}};
    source = fmt::format("Newtonian {:g} Pa.s", a.mu);
  } else if (!a.material.empty()) {
    if (!std::isfinite(T_K)) throw InputError("--material needs the melt --temperature (degC)");
    std::string m = a.material;
    for (auto& c : m) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (m == "peek-power-law") {
      const auto pl = fitting::holtrup_peek_power_law(a.temperature_degc);
      spec.model = fitting::ViscosityModel::power_law;
      spec.values = {{"K_Pa_s_n", pl.K_Pa_s_n}, {"n", pl.n}};
      source = fmt::format("Holtrup 2019 eq. 5.10/5.11 at {:g} degC: K {:.6g} Pa.s^n, n {:.5f}", a.temperature_degc,
                           pl.K_Pa_s_n, pl.n);
    } else {
      const auto& mat = fitting::cross_wlf_material(a.material);
      spec = fitting::ViscositySpec::from_cross_wlf(mat.params);
      source = mat.name + " Cross-WLF (Holtrup 2019 Table 2.4 / appendix A)";
      if (mat.T_min_K > 0 && (T_K < mat.T_min_K || T_K > mat.T_max_K))
        outcome.warnings.push_back(fmt::format("{:.2f} K is outside {}'s validity range {:g}..{:g} K", T_K, mat.name,
                                               mat.T_min_K, mat.T_max_K));
    }
  } else {
    if (!std::isfinite(T_K)) throw InputError("--rheology needs the melt --temperature (degC)");
    std::string bytes;
    const nlohmann::json j = read_json_file(a.rheology_json, &bytes);  // a syntax error is located there
    outcome.input_path = a.rheology_json;
    outcome.input_sha256 = sha256_hex(bytes);
    outcome.input_size_bytes = bytes.size();
    try {
      const auto& r = j.contains("results") ? j["results"] : j;
      spec = fitting::parse_viscosity_spec_name(r.at("model").get<std::string>());
      for (const auto& [k, v] : r.at("params").items()) spec.values[k] = v.at("value").get<double>();
      source = "fit " + r.at("model").get<std::string>() + " from " + a.rheology_json;
    } catch (const nlohmann::json::exception& e) {
      throw InputError(std::string("not a 'tunekit rheo --json' result: ") + core::plain_json_error(e.what()),
                       a.rheology_json);
    }
    require_rheology_params(spec, a.rheology_json);
  }
  const double T_eval = std::isfinite(T_K) ? T_K : 0.0;
  if (spec.model != fitting::ViscosityModel::power_law && spec.model != fitting::ViscosityModel::newtonian &&
      !std::isfinite(T_K))
    throw InputError("this rheology is temperature dependent; give --temperature (degC)");

  for (double q : a.flows_mm3_s) {
    if (!(q > 0)) throw InputError(fmt::format("--flow must be positive (got {:g} mm3/s)", q));
    const double Q = q * 1e-9;
    NozzlePoint pt;
    pt.flow_mm3_s = q;
    pt.local = fitting::local_power_law(spec, Q, g.d_m, T_eval);
    for (auto m : {fitting::PressureModel::hagen_poiseuille, fitting::PressureModel::power_law_capillary,
                   fitting::PressureModel::bellini, fitting::PressureModel::boles})
      pt.all_models_Pa[fitting::to_string(m)] = fitting::pressure_drop(m, spec, Q, T_eval, g);
    pt.pressure_drop_Pa = fitting::pressure_drop(model, spec, Q, T_eval, g);
    out.points.push_back(std::move(pt));
  }
  out.temperature_K = T_K;
  if (std::isfinite(T_K) || spec.model == fitting::ViscosityModel::power_law) {
    ident::LiquefierPredictionOptions po = a.prediction;
    po.temperature_K = std::isfinite(T_K) ? T_K : 1.0;  // a power law without shift ignores it
    po.flows_mm3_s = a.flows_mm3_s;
    out.prediction = ident::predict_liquefier(spec, po);
  }
  return out;
}

}  // namespace

NozzleOutcome compute_nozzle(const NozzleOptions& a) {
  NozzleOutcome outcome;
  outcome.options = a;
  if (!(a.kelvin_offset == fitting::kKelvinOffset || a.kelvin_offset == fitting::kKelvinOffsetThesis))
    throw InputError("--kelvin-offset must be 273.15 (SI) or 273 (Holtrup's (2019) code)");
  if (!a.fit_file.empty()) outcome.fit = compute_nozzle_fit(a, outcome);
  else outcome.forward = compute_nozzle_forward(a, outcome);
  return outcome;
}

Envelope to_envelope(const NozzleOutcome& o) {
  const NozzleOptions& a = o.options;
  const std::string model = fitting::to_string(a.prediction.model);
  Envelope env("nozzle");
  env.set_options({{"model", model},
                   {"geometry", nozzle_geometry_json(a.prediction.geometry)},
                   {"kelvin_offset", a.kelvin_offset},
                   {"material", a.material},
                   {"reference_flow_mm3_s", a.prediction.reference_flow_mm3_s}});
  if (!o.input_path.empty()) env.add_input_digest(o.input_path, o.input_sha256, o.input_size_bytes);
  auto& res = env.results();
  if (o.fit) {
    res = fitting::to_json(o.fit->fit);
  } else if (o.forward) {
    const NozzleForward& f = *o.forward;
    res["rheology"] = f.rheology;
    if (std::isfinite(f.temperature_K)) res["temperature_K"] = f.temperature_K;
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& p : f.points) {
      nlohmann::json all;
      for (const auto& [name, dp] : p.all_models_Pa) all[name] = dp;
      rows.push_back({{"flow_mm3_s", p.flow_mm3_s},
                      {"pressure_drop_Pa", p.pressure_drop_Pa},
                      {"pressure_drop_MPa", p.pressure_drop_Pa * 1e-6},
                      {"wall_shear_rate_1_s", p.local.wall_shear_rate_1_s},
                      {"K_Pa_s_n", p.local.K_Pa_s_n},
                      {"n", p.local.n},
                      {"all_models_Pa", all}});
    }
    res["points"] = rows;
    if (f.prediction) res["prediction"] = ident::to_json(*f.prediction);
  }
  res["geometry"] = nozzle_geometry_json(a.prediction.geometry);
  res["pressure_model"] = model;
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

void print_text(const NozzleOutcome& o, std::ostream& os) {
  const NozzleOptions& a = o.options;
  if (o.fit) {
    const auto& fit = o.fit->fit;
    os << fmt::format("{}: {} measurements, {} model\n", a.fit_file, o.fit->rows, fit.model);
    for (const auto& q : fit.params) {
      if (q.fixed)
        os << fmt::format("  {:<14} {:>12.6g} {:<8} (held: the reference, not estimated)\n", q.name, q.value, q.unit);
      else
        os << fmt::format("  {:<14} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]\n", q.name, q.value, q.unit, q.ci95_lo,
                          q.ci95_hi);
    }
    os << fmt::format("  rms(ln dP) {:.4g}, R2 {:.5f}\n", fit.diagnostics.rms, fit.diagnostics.r2);
    return;
  }
  if (!o.forward) return;
  const auto& g = a.prediction.geometry;
  os << fmt::format("{} pressure drop, {}\n", fitting::to_string(a.prediction.model), o.forward->rheology);
  os << fmt::format("  nozzle d {:g} mm, l {:g} mm, cone half angle {:g} deg, D {:g} mm\n",
                    nozzle_display_value(g.d_m, 1e3), nozzle_display_value(g.l_m, 1e3),
                    nozzle_display_value(g.cone_half_angle_rad, 1 / kNozzleRadPerDeg),
                    nozzle_display_value(g.D_m, 1e3));
  for (const auto& p : o.forward->points)
    os << fmt::format("  Q {:8.4g} mm3/s: dP {:8.4f} MPa (wall shear rate {:.4g} 1/s)\n", p.flow_mm3_s,
                      p.pressure_drop_Pa * 1e-6, p.local.wall_shear_rate_1_s);
}

}  // namespace tunekit::calibration
