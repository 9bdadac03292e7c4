// tunekit nozzle: the pressure drop of a melt through a nozzle (Hagen-Poiseuille, power-law
// capillary with the Rabinowitsch correction, Bellini's three-zone model, Boles' model) from
// rheology and geometry, and the inverse fit of K and n from measured flow and pressure (or
// feeder force) at known temperature, as in the load-cell experiments of Holtrup 2019 sec. 5.3.
#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/nozzle_pressure.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/ident/rheology_data.hpp"

namespace tunekit::cli {
namespace {

struct NozzleArgs {
  std::string model = "boles";
  double K = fitting::kNaN, n = fitting::kNaN, mu = fitting::kNaN;
  std::string material;
  std::string rheology_json;
  double temperature_degc = fitting::kNaN;
  double kelvin_offset = fitting::kKelvinOffset;
  std::vector<double> flows_mm3_s;
  double reference_flow_mm3_s = 3.0;
  double d_mm = 0.6, l_mm = 4.0, cone_deg = 30.0, D_mm = 5.0, melt_length_mm = 10.0;
  std::string fit_file;
  double piston_diameter_mm = fitting::kNaN;
  OutputOptions output;
};

fitting::NozzleGeometry geometry_of(const NozzleArgs& a) {
  fitting::NozzleGeometry g;
  g.d_m = a.d_mm * 1e-3;
  g.l_m = a.l_mm * 1e-3;
  g.cone_half_angle_rad = a.cone_deg * std::numbers::pi / 180.0;
  g.D_m = a.D_mm * 1e-3;
  g.melt_length_m = a.melt_length_mm * 1e-3;
  fitting::validate(g);
  return g;
}

nlohmann::json geometry_json(const NozzleArgs& a) {
  return {{"d_mm", a.d_mm}, {"l_mm", a.l_mm}, {"cone_half_angle_deg", a.cone_deg}, {"D_mm", a.D_mm},
          {"melt_length_mm", a.melt_length_mm}};
}

int run_fit(const NozzleArgs& a, CliContext& ctx, Envelope& env) {
  const std::string bytes = ident::read_file_bytes(a.fit_file);
  env.add_input(a.fit_file, bytes);
  const auto t = ident::parse_csv(bytes, a.fit_file);
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
    const double pf = ident::pressure_unit_factor(pc.unit);
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
        if (v < 273.15) throw InputError(fmt::format("temperature {:g} K is below 0 degC; the values look like degC", v), hdr);
        T.push_back(v);
      } else if (tc.unit == "degC" || tc.unit == "C") {
        if (v > 600) throw InputError(fmt::format("temperature {:g} degC is above 600 degC; the values look like kelvin", v), hdr);
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
  const auto model = fitting::parse_pressure_model(a.model);
  const auto fit = fitting::fit_nozzle_rheology(d, model, geometry_of(a));
  auto& res = env.results();
  res = fitting::to_json(fit);
  res["geometry"] = geometry_json(a);
  res["pressure_model"] = fitting::to_string(model);
  for (const auto& w : fit.warnings) env.warn(w);
  if (!a.output.json) {
    ctx.out << fmt::format("{}: {} measurements, {} model\n", a.fit_file, t.rows, fit.model);
    for (const auto& q : fit.params)
      ctx.out << fmt::format("  {:<14} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]\n", q.name, q.value, q.unit, q.ci95_lo, q.ci95_hi);
    ctx.out << fmt::format("  rms(ln dP) {:.4g}, R2 {:.5f}\n", fit.diagnostics.rms, fit.diagnostics.r2);
  }
  return emit(env, a.output, ctx);
}

int run_nozzle(const NozzleArgs& a, CliContext& ctx) {
  Envelope env("nozzle");
  env.set_options({{"model", a.model},
                   {"geometry", geometry_json(a)},
                   {"kelvin_offset", a.kelvin_offset},
                   {"material", a.material},
                   {"reference_flow_mm3_s", a.reference_flow_mm3_s}});
  if (!(a.kelvin_offset == fitting::kKelvinOffset || a.kelvin_offset == fitting::kKelvinOffsetThesis))
    throw InputError("--kelvin-offset must be 273.15 (SI) or 273 (Holtrup's (2019) code)");
  if (!a.fit_file.empty()) return run_fit(a, ctx, env);

  const auto g = geometry_of(a);
  const auto model = fitting::parse_pressure_model(a.model);
  const int sources = (std::isfinite(a.K) || std::isfinite(a.n) ? 1 : 0) + (std::isfinite(a.mu) ? 1 : 0) +
                      (a.material.empty() ? 0 : 1) + (a.rheology_json.empty() ? 0 : 1);
  if (sources != 1)
    throw InputError("give the rheology one way: --K and --n, --mu, --material NAME, or --rheology FIT.json");
  if (a.flows_mm3_s.empty()) throw InputError("give at least one --flow (mm3/s)");
  const double T_K = std::isfinite(a.temperature_degc) ? a.temperature_degc + a.kelvin_offset : fitting::kNaN;

  // Every source becomes a viscosity function of shear rate and temperature.
  fitting::ViscositySpec spec;
  std::string source;
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
        env.warn(fmt::format("{:.2f} K is outside {}'s validity range {:g}..{:g} K", T_K, mat.name, mat.T_min_K, mat.T_max_K));
    }
  } else {
    if (!std::isfinite(T_K)) throw InputError("--rheology needs the melt --temperature (degC)");
    const std::string bytes = ident::read_file_bytes(a.rheology_json);
    env.add_input(a.rheology_json, bytes);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(bytes);
      const auto& r = j.contains("results") ? j["results"] : j;
      spec = fitting::parse_viscosity_spec_name(r.at("model").get<std::string>());
      for (const auto& [k, v] : r.at("params").items()) spec.values[k] = v.at("value").get<double>();
      source = "fit " + r.at("model").get<std::string>() + " from " + a.rheology_json;
    } catch (const nlohmann::json::exception& e) {
      throw InputError(std::string("not a 'tunekit rheo --json' result: ") + e.what(), a.rheology_json);
    }
  }
  const double T_eval = std::isfinite(T_K) ? T_K : 0.0;
  if (spec.model != fitting::ViscosityModel::power_law && spec.model != fitting::ViscosityModel::newtonian &&
      !std::isfinite(T_K))
    throw InputError("this rheology is temperature dependent; give --temperature (degC)");

  nlohmann::json rows = nlohmann::json::array();
  std::vector<double> dps;
  for (double q : a.flows_mm3_s) {
    if (!(q > 0)) throw InputError(fmt::format("--flow must be positive (got {:g} mm3/s)", q));
    const double Q = q * 1e-9;
    const auto lp = fitting::local_power_law(spec, Q, g.d_m, T_eval);
    nlohmann::json all;
    for (auto m : {fitting::PressureModel::hagen_poiseuille, fitting::PressureModel::power_law_capillary,
                   fitting::PressureModel::bellini, fitting::PressureModel::boles})
      all[fitting::to_string(m)] = fitting::pressure_drop(m, spec, Q, T_eval, g);
    const double dp = fitting::pressure_drop(model, spec, Q, T_eval, g);
    dps.push_back(dp);
    rows.push_back({{"flow_mm3_s", q},
                    {"pressure_drop_Pa", dp},
                    {"pressure_drop_MPa", dp * 1e-6},
                    {"wall_shear_rate_1_s", lp.wall_shear_rate_1_s},
                    {"K_Pa_s_n", lp.K_Pa_s_n},
                    {"n", lp.n},
                    {"all_models_Pa", all}});
  }
  auto& res = env.results();
  res["pressure_model"] = fitting::to_string(model);
  res["rheology"] = source;
  res["geometry"] = geometry_json(a);
  if (std::isfinite(T_K)) res["temperature_K"] = T_K;
  res["points"] = rows;
  if (std::isfinite(T_K) || spec.model == fitting::ViscosityModel::power_law) {
    ident::LiquefierPredictionOptions po;
    po.geometry = g;
    po.model = model;
    po.temperature_K = std::isfinite(T_K) ? T_K : 1.0;  // a power law without shift ignores it
    po.flows_mm3_s = a.flows_mm3_s;
    po.reference_flow_mm3_s = a.reference_flow_mm3_s;
    res["prediction"] = ident::to_json(ident::predict_liquefier(spec, po));
  }
  if (!a.output.json) {
    ctx.out << fmt::format("{} pressure drop, {}\n", fitting::to_string(model), source);
    ctx.out << fmt::format("  nozzle d {:g} mm, l {:g} mm, cone half angle {:g} deg, D {:g} mm\n", a.d_mm, a.l_mm, a.cone_deg, a.D_mm);
    for (std::size_t i = 0; i < rows.size(); ++i)
      ctx.out << fmt::format("  Q {:8.4g} mm3/s: dP {:8.4f} MPa (wall shear rate {:.4g} 1/s)\n", a.flows_mm3_s[i],
                             dps[i] * 1e-6, rows[i]["wall_shear_rate_1_s"].get<double>());
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_nozzle(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<NozzleArgs>();
  auto* sub = app.add_subcommand("nozzle", "Nozzle pressure drop from rheology and geometry, and its inverse fit");
  sub->add_option("--model", args->model, "Pressure-drop model: boles, bellini, power-law (capillary, Rabinowitsch) or hagen-poiseuille")
      ->capture_default_str();
  sub->add_option("--K", args->K, "Power-law consistency K (Pa.s^n)");
  sub->add_option("--n", args->n, "Power-law index n (1)");
  sub->add_option("--mu", args->mu, "Newtonian viscosity (Pa.s)");
  sub->add_option("--material", args->material,
                  "Cross-WLF material of Holtrup 2019 (PEEK, ABS, ULTEM1010) or peek-power-law (eq. 5.10/5.11); needs --temperature");
  sub->add_option("--rheology", args->rheology_json, "A 'tunekit rheo --json' result file to take the viscosity model from");
  sub->add_option("-T,--temperature", args->temperature_degc, "Melt temperature (degC)");
  sub->add_option("--kelvin-offset", args->kelvin_offset, "degC to K offset: 273.15 (SI) or 273 (Holtrup's (2019) code) (K)")
      ->capture_default_str();
  sub->add_option("-Q,--flow", args->flows_mm3_s, "Volumetric flow at the nozzle exit (mm3/s); repeatable");
  sub->add_option("--reference-flow", args->reference_flow_mm3_s, "Flow at which relative_tau is 1 (mm3/s)")->capture_default_str();
  sub->add_option("--nozzle-d", args->d_mm, "Nozzle channel diameter d (mm)")->capture_default_str();
  sub->add_option("--nozzle-l", args->l_mm, "Nozzle land length l (mm)")->capture_default_str();
  sub->add_option("--cone-angle", args->cone_deg, "Cone half angle alpha (degrees; Bellini's beta is twice this)")->capture_default_str();
  sub->add_option("--entrance-D", args->D_mm, "Melt room / entrance diameter D (mm)")->capture_default_str();
  sub->add_option("--melt-length", args->melt_length_mm, "Bellini's melt room length L1 (mm)")->capture_default_str();
  sub->add_option("--fit", args->fit_file,
                  "Inverse fit: CSV with flow (mm3/s), pressure (MPa|Pa|bar) or force (N), temperature (degC|K)");
  sub->add_option("--piston-diameter", args->piston_diameter_mm, "Diameter the feeder force acts on (mm), for a force column");
  add_output_options(sub, args->output);
  sub->footer(
      "Defaults are Holtrup's (2019) regular nozzle (Table 5.3): d 0.6 mm, l 4 mm, alpha 30 deg, D 5 mm.\n"
      "Examples:\n"
      "  tunekit nozzle --K 10114 --n 0.51 --flow 20 --cone-angle 45          # appendix F: 12.16 MPa\n"
      "  tunekit nozzle --material peek-power-law -T 405 --flow 3             # sec. 5.2.3: 4.98 MPa\n"
      "  tunekit nozzle --material PEEK -T 405 --flow 1.5 --flow 3 --flow 6 --model bellini --json\n"
      "  tunekit nozzle --rheology peek_fit.json -T 405 --flow 3 --json       # results.prediction\n"
      "  tunekit nozzle --fit datasets/rheology/nozzle_pressure_synthetic.csv --json   # fit K, n (and Ea)");
  sub->callback([args, &ctx] { set_exit_code(run_nozzle(*args, ctx)); });
}

}  // namespace tunekit::cli
