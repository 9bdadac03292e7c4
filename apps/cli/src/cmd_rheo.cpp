// tunekit rheo: fit melt viscosity models (Newtonian, power law, Cross, Cross-WLF,
// Carreau-Yasuda, with Arrhenius or WLF temperature shifts) to rheometer data, compare them by
// AIC, fit power laws over a shear-rate window, build a TTS master curve, and predict the
// liquefier's flow-dependent resistance and time constant for a nozzle geometry.
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <tuple>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/ident/rheology_data.hpp"

namespace tunekit::cli {
namespace {

using fitting::kNaN;

struct RheoArgs {
  std::string file;
  std::string model = "auto";
  std::string shift = "auto";
  double t_ref_degc = kNaN;
  double temperature_degc = kNaN;
  double kelvin_offset = fitting::kKelvinOffset;
  std::string temperatures;  // LO:HI degC
  std::vector<std::string> fix;
  std::vector<std::string> free;
  bool no_compare = false;
  bool tts = false;
  std::string window;
  int window_points = 50;
  std::vector<double> window_at_degc;
  // Nozzle geometry for the liquefier prediction (mm, degrees).
  double nozzle_d_mm = kNaN;
  double nozzle_l_mm = 4.0;
  double cone_angle_deg = 30.0;
  double entrance_D_mm = 5.0;
  double predict_at_degc = kNaN;
  std::vector<double> flows_mm3_s;
  double reference_flow_mm3_s = 3.0;
  std::string pressure_model = "boles";
  std::string shear_rate_column, viscosity_column, stress_column, temperature_column, pressure_column;
  std::string viscosity_unit, stress_unit, temperature_unit;
  OutputOptions output;
};

std::pair<double, double> parse_window(const std::string& s) {
  const auto c = s.find(':');
  if (c == std::string::npos) throw InputError("--power-law-window: expected LOW:HIGH in 1/s, e.g. 600:950");
  try {
    return {std::stod(s.substr(0, c)), std::stod(s.substr(c + 1))};
  } catch (const std::exception&) {
    throw InputError("--power-law-window: expected LOW:HIGH in 1/s, e.g. 600:950 (got '" + s + "')");
  }
}

// "LO:HI" in degC; either side may be empty (no limit).
std::pair<double, double> parse_temperature_range(const std::string& s) {
  const auto c = s.find(':');
  const auto bad = [&] {
    return InputError("--temperatures: expected LO:HI in degC, e.g. 300:350 (either side may be empty), got '" + s + "'");
  };
  if (c == std::string::npos) throw bad();
  auto side = [&](const std::string& x) {
    if (x.empty()) return kNaN;
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(x, &used);
    } catch (const std::exception&) {
      throw bad();
    }
    if (used != x.size() || !std::isfinite(v)) throw bad();
    return v;
  };
  const double lo = side(s.substr(0, c)), hi = side(s.substr(c + 1));
  if (std::isfinite(lo) && std::isfinite(hi) && lo > hi) throw bad();
  return {lo, hi};
}

std::map<std::string, double> parse_fixes(const std::vector<std::string>& fixes) {
  std::map<std::string, double> m;
  for (const auto& f : fixes) {
    const auto eq = f.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--fix: expected NAME=VALUE (SI units), got '" + f + "'");
    try {
      std::size_t used = 0;
      const double v = std::stod(f.substr(eq + 1), &used);
      if (used != f.size() - eq - 1) throw std::invalid_argument("trailing");
      m[f.substr(0, eq)] = v;
    } catch (const std::exception&) {
      throw InputError("--fix: '" + f.substr(eq + 1) + "' is not a number");
    }
  }
  return m;
}

int run_rheo(const RheoArgs& a, CliContext& ctx) {
  const std::string bytes = ident::read_file_bytes(a.file);
  ident::RheologyCsvOptions co;
  co.temperature_degC = a.temperature_degc;
  co.kelvin_offset = a.kelvin_offset;
  co.shear_rate_column = a.shear_rate_column;
  co.viscosity_column = a.viscosity_column;
  co.stress_column = a.stress_column;
  co.temperature_column = a.temperature_column;
  co.pressure_column = a.pressure_column;
  co.viscosity_unit = a.viscosity_unit;
  co.stress_unit = a.stress_unit;
  co.temperature_unit = a.temperature_unit;
  if (!a.viscosity_column.empty() && !a.stress_column.empty())
    throw InputError("give --viscosity or --shear-stress, not both");
  if (!a.temperatures.empty()) std::tie(co.temperature_min_degC, co.temperature_max_degC) = parse_temperature_range(a.temperatures);
  if (!(a.kelvin_offset == fitting::kKelvinOffset || a.kelvin_offset == fitting::kKelvinOffsetThesis))
    throw InputError("--kelvin-offset must be 273.15 (SI) or 273 (Holtrup's (2019) code)");
  const auto table = ident::parse_rheology_csv(bytes, a.file, co);
  const auto& data = table.data;
  const auto levels = data.temperature_levels_K();
  const bool multi = levels.size() > 1;

  fitting::ViscosityFitOptions primary;
  primary.fixed = parse_fixes(a.fix);
  primary.free = a.free;
  primary.T_ref_K = std::isfinite(a.t_ref_degc) ? a.t_ref_degc + a.kelvin_offset : kNaN;
  const bool auto_model = a.model == "auto";
  if (!auto_model) primary.model = fitting::parse_viscosity_model(a.model);
  if (a.shift == "auto")
    primary.shift = (multi && primary.model != fitting::ViscosityModel::cross_wlf) ? fitting::TemperatureShift::arrhenius
                                                                                  : fitting::TemperatureShift::none;
  else
    primary.shift = fitting::parse_temperature_shift(a.shift);
  if (primary.model == fitting::ViscosityModel::cross_wlf && primary.shift != fitting::TemperatureShift::none)
    throw InputError("--shift: cross-wlf carries its own (WLF) temperature dependence; leave --shift at auto or none");
  if (auto_model && (!a.fix.empty() || !a.free.empty()))
    throw InputError("--fix/--free name parameters of one model; choose it with --model");
  if (auto_model && a.no_compare) throw InputError("--model auto picks the best model by AIC; it cannot be combined with --no-compare");

  Envelope env("rheo");
  env.add_input(a.file, bytes);
  env.set_options({{"model", a.model},
                   {"shift", a.shift},
                   {"kelvin_offset", a.kelvin_offset},
                   {"viscosity_unit", a.viscosity_unit},
                   {"temperatures_degC", a.temperatures},
                   {"fix", a.fix},
                   {"free", a.free},
                   {"compare", !a.no_compare},
                   {"tts", a.tts},
                   {"power_law_window", a.window},
                   {"power_law_points", a.window_points},
                   {"nozzle_d_mm", std::isfinite(a.nozzle_d_mm) ? nlohmann::json(a.nozzle_d_mm) : nlohmann::json()},
                   {"nozzle_l_mm", a.nozzle_l_mm},
                   {"cone_angle_deg", a.cone_angle_deg},
                   {"entrance_D_mm", a.entrance_D_mm},
                   {"reference_flow_mm3_s", a.reference_flow_mm3_s},
                   {"pressure_model", a.pressure_model},
                   {"columns",
                    {{"shear_rate", a.shear_rate_column},
                     {"viscosity", a.viscosity_column},
                     {"shear_stress", a.stress_column},
                     {"temperature", a.temperature_column},
                     {"pressure", a.pressure_column}}},
                   {"units",
                    {{"viscosity", a.viscosity_unit}, {"shear_stress", a.stress_unit}, {"temperature", a.temperature_unit}}}});
  for (const auto& n : table.notes) env.warn(a.file + ": " + n);
  for (const auto& w : table.warnings) env.warn(w);

  fitting::FitResult fit;
  nlohmann::json comparison;
  if (auto_model || !a.no_compare) {
    auto cands = fitting::default_candidates(data, primary);
    if (!auto_model) {
      // The requested configuration replaces its default twin (it may carry --fix/--free).
      const std::string want = fitting::ViscositySpec{primary.model, primary.shift, {}}.name();
      cands.erase(std::remove_if(cands.begin(), cands.end(),
                                 [&](const auto& c) { return fitting::ViscositySpec{c.model, c.shift, {}}.name() == want; }),
                  cands.end());
      fit = fitting::fit_viscosity(data, primary);  // throws with the reason when it cannot be fitted
      cands.insert(cands.begin(), primary);
    }
    const auto cmp = fitting::compare_viscosity_models(data, cands);
    comparison = fitting::to_json(cmp);
    if (auto_model) {
      if (cmp.best.empty()) {
        std::string why;
        for (const auto& e : cmp.entries)
          why += (why.empty() ? "" : "; ") + e.model + ": " + (e.error.empty() ? "no reason given" : e.error);
        throw FitError("no viscosity model could be fitted (" + why + ")", a.file);
      }
      for (std::size_t i = 0; i < cmp.entries.size(); ++i)
        if (cmp.entries[i].model == cmp.best) fit = cmp.fits[i];
    }
  } else {
    fit = fitting::fit_viscosity(data, primary);
  }
  const auto spec = fitting::spec_from_fit(fit);

  auto& res = env.results();
  res = fitting::to_json(fit);
  res["temperatures_K"] = levels;
  res["num_points"] = data.size();
  res["kelvin_offset"] = a.kelvin_offset;
  if (!comparison.is_null()) res["model_comparison"] = comparison;
  for (const auto& w : fit.warnings) env.warn(w);

  const double T_mid = levels[(levels.size() - 1) / 2];
  if (!a.window.empty()) {
    const auto [lo, hi] = parse_window(a.window);
    std::vector<double> temps;
    for (double c : a.window_at_degc) temps.push_back(c + a.kelvin_offset);
    if (temps.empty()) temps = levels;
    nlohmann::json fits = nlohmann::json::array();
    for (double T : temps) {
      auto pl = fitting::fit_power_law_window(spec, T, lo, hi, a.window_points);
      auto j = fitting::to_json(pl);
      j["temperature_K"] = T;
      fits.push_back(j);
    }
    res["power_law"] = {{"window_1_s", {lo, hi}}, {"points", a.window_points}, {"spacing", "log"}, {"fits", fits}};
  }
  if (a.tts && !multi) throw InputError("--tts needs data at two or more temperatures", a.file);
  if (multi) {
    // Do the temperatures superpose? A transition or a degraded sample shows here, and a
    // temperature model fitted across it describes neither side.
    try {
      const auto sc = fitting::check_superposition(data, primary.T_ref_K);
      res["superposition"] = fitting::to_json(sc);
      if (a.tts) res["tts"] = fitting::to_json(sc.tts);
      const auto degc = [&](double K) { return fmt::format("{:g} degC", std::round((K - a.kelvin_offset) * 100) / 100); };
      std::string off;
      for (const auto& l : sc.levels)
        if (!l.on_master_curve) off += (off.empty() ? "" : ", ") + degc(l.temperature_K);
      if (!off.empty())
        env.warn(fmt::format("the curves at {} do not lie on the master curve of the other temperatures (F test, p < {:g}): "
                             "a transition, a degraded sample or a change of mechanism; one temperature-shift model "
                             "cannot hold them (select a range with --temperatures)",
                             off, sc.alpha));
      for (const auto& r : sc.reversals)
        env.warn(fmt::format("the viscosity rises between {} and {} (shift factor x{:.3g}): a transition between these "
                             "temperatures (e.g. a liquid-crystalline melt turning isotropic) or curves of different samples; "
                             "fit each side on its own with --temperatures",
                             degc(r.lower_K), degc(r.upper_K), r.ratio));
    } catch (const Error& e) {
      if (a.tts) throw;
      env.warn("superposition check not done: " + e.message());
    }
  }
  if (auto corr = fitting::correlation_json(fit); !corr.is_null()) res["correlation"] = corr;
  if (std::isfinite(a.nozzle_d_mm)) {
    ident::LiquefierPredictionOptions po;
    po.geometry.d_m = a.nozzle_d_mm * 1e-3;
    po.geometry.l_m = a.nozzle_l_mm * 1e-3;
    po.geometry.cone_half_angle_rad = a.cone_angle_deg * std::numbers::pi / 180.0;
    po.geometry.D_m = a.entrance_D_mm * 1e-3;
    po.model = fitting::parse_pressure_model(a.pressure_model);
    po.temperature_K = std::isfinite(a.predict_at_degc) ? a.predict_at_degc + a.kelvin_offset : T_mid;
    if (!a.flows_mm3_s.empty()) po.flows_mm3_s = a.flows_mm3_s;
    po.reference_flow_mm3_s = a.reference_flow_mm3_s;
    res["prediction"] = ident::to_json(ident::predict_liquefier(spec, po));
  }

  if (!a.output.json) {
    ctx.out << fmt::format("{}: {} points at {} temperature(s); model {}\n", a.file, data.size(), levels.size(), fit.model);
    for (const auto& p : fit.params) {
      if (p.fixed)
        ctx.out << fmt::format("  {:<14} {:>12.6g} {:<8} (held)\n", p.name, p.value, p.unit);
      else
        ctx.out << fmt::format("  {:<14} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]{}\n", p.name, p.value, p.unit, p.ci95_lo,
                               p.ci95_hi, p.ci95_method == "profile-likelihood" ? " (profile likelihood)" : "");
    }
    for (const auto& p : fit.derived)
      ctx.out << fmt::format("  {:<26} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]\n", p.name, p.value, p.unit, p.ci95_lo,
                             p.ci95_hi);
    if (res.contains("superposition"))
      for (const auto& l : res["superposition"]["levels"])
        ctx.out << fmt::format("  a_T at {:.2f} K: {:.4g} [{:.4g}, {:.4g}]{}\n", l["temperature_K"].get<double>(),
                               l["a_T"].get<double>(), l["a_T_ci95"][0].get<double>(), l["a_T_ci95"][1].get<double>(),
                               l["on_master_curve"].get<bool>() ? "" : "  NOT on the master curve");
    ctx.out << fmt::format("  rms(ln eta) {:.4g}, R2 {:.5f}, AIC {:.2f}\n", fit.diagnostics.rms, fit.diagnostics.r2,
                           fit.diagnostics.aic);
    if (res.contains("model_comparison")) {
      ctx.out << "  model comparison (AIC):\n";
      for (const auto& e : res["model_comparison"]["models"]) {
        if (e["ok"].get<bool>())
          ctx.out << fmt::format("    {:<26} k={} dAIC {:8.2f} weight {:.3f}\n", e["model"].get<std::string>(),
                                 e["num_parameters"].get<int>(), e["delta_aic"].get<double>(),
                                 e["akaike_weight"].get<double>());
        else
          ctx.out << fmt::format("    {:<26} not fitted: {}\n", e["model"].get<std::string>(), e["error"].get<std::string>());
      }
    }
    if (res.contains("power_law"))
      for (const auto& f : res["power_law"]["fits"])
        ctx.out << fmt::format("  power law at {:.2f} K: K {:.6g} Pa.s^n, n {:.5f}\n", f["temperature_K"].get<double>(),
                               f["params"]["K_Pa_s_n"]["value"].get<double>(), f["params"]["n"]["value"].get<double>());
    if (res.contains("prediction")) {
      const auto& p = res["prediction"];
      ctx.out << fmt::format("  liquefier at {:.2f} K ({}): flow mm3/s, dP MPa, dP/dQ Pa.s/mm3, relative tau\n",
                             p["temperature_K"].get<double>(), p["pressure_model"].get<std::string>());
      for (std::size_t i = 0; i < p["flow_mm3_s"].size(); ++i)
        ctx.out << fmt::format("    {:8.3g} {:10.4g} {:12.5g} {:8.4f}\n", p["flow_mm3_s"][i].get<double>(),
                               p["pressure_drop_Pa"][i].get<double>() * 1e-6, p["dP_dQ_Pa_s_per_mm3"][i].get<double>(),
                               p["relative_tau"][i].get<double>());
    }
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_rheo(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<RheoArgs>();
  auto* sub = app.add_subcommand("rheo", "Fit melt viscosity models (power law, Cross, Cross-WLF, Carreau-Yasuda)");
  sub->add_option("file", args->file,
                  "CSV with shear_rate (1/s), viscosity (Pa.s|mPa.s) or shear_stress (Pa), temperature (degC|K), "
                  "optional pressure (Pa) and weight")
      ->required();
  sub->add_option("-m,--model", args->model,
                  "newtonian, power-law, cross, cross-wlf, carreau-yasuda, or auto (lowest AIC)")
      ->capture_default_str();
  sub->add_option("--shift", args->shift,
                  "Temperature shift for models other than cross-wlf: none, arrhenius, wlf, or auto "
                  "(arrhenius when the data hold several temperatures)")
      ->capture_default_str();
  sub->add_option("--shear-rate", args->shear_rate_column, "Shear-rate column (1/s) when not named shear_rate");
  sub->add_option("--viscosity", args->viscosity_column, "Viscosity column when not named viscosity or eta");
  sub->add_option("--shear-stress", args->stress_column, "Shear-stress column (viscosity = stress / shear rate)");
  sub->add_option("--temperature-col", args->temperature_column, "Temperature column when not named temperature");
  sub->add_option("--pressure-col", args->pressure_column, "Pressure column when not named pressure");
  sub->add_option("--stress-unit", args->stress_unit, "Unit of the shear-stress column: Pa, kPa, MPa");
  sub->add_option("--temperature-unit", args->temperature_unit, "Unit of the temperature column: degC or K");
  sub->add_option("--t-ref", args->t_ref_degc, "Reference temperature of the shift (degC; default: the middle data temperature)");
  sub->add_option("--temperature", args->temperature_degc, "Temperature of every point when the file has no temperature column (degC)");
  sub->add_option("--kelvin-offset", args->kelvin_offset, "degC to K offset: 273.15 (SI) or 273 (as Holtrup's (2019) code) (K)")
      ->capture_default_str();
  sub->add_option("--viscosity-unit", args->viscosity_unit,
                  "Unit of the viscosity column when its header states none: Pa.s, mPa.s, cP, P (poise) or kPa.s");
  sub->add_option("--temperatures", args->temperatures,
                  "Fit only the rows at LO:HI degC (inclusive; either side may be empty), e.g. 300:350");
  sub->add_option("--fix", args->fix,
                  "Hold a parameter at a value, NAME=VALUE in the parameter's SI unit (e.g. D2_K=416); repeatable. "
                  "cross-wlf holds A2_K=51.6 K and D3_K_per_Pa=0 by default");
  sub->add_option("--free", args->free, "Estimate a parameter held by default (A2_K, D3_K_per_Pa, eta_inf_Pa_s); repeatable");
  sub->add_flag("--no-compare", args->no_compare, "Fit only the chosen model (no AIC comparison)");
  sub->add_flag("--tts", args->tts, "Time-temperature superposition: shift factors a_T (1) and the master curve");
  sub->add_option("--power-law-window", args->window,
                  "Fit K (Pa.s^n) and n of a power law to the fitted model over LOW:HIGH shear rates (1/s), e.g. 600:950");
  sub->add_option("--power-law-points", args->window_points, "Log-spaced points in the power-law window (count)")
      ->capture_default_str();
  sub->add_option("--power-law-at", args->window_at_degc, "Temperatures of the power-law fits (degC; default: the data's)");
  sub->add_option("--nozzle-d", args->nozzle_d_mm, "Nozzle channel diameter d (mm); enables the liquefier prediction");
  sub->add_option("--nozzle-l", args->nozzle_l_mm, "Nozzle land length l (mm)")->capture_default_str();
  sub->add_option("--cone-angle", args->cone_angle_deg, "Nozzle cone half angle alpha (degrees)")->capture_default_str();
  sub->add_option("--entrance-D", args->entrance_D_mm, "Melt room / entrance diameter D (mm)")->capture_default_str();
  sub->add_option("--predict-at", args->predict_at_degc, "Melt temperature of the prediction (degC; default: the middle data temperature)");
  sub->add_option("--flows", args->flows_mm3_s, "Operating flows of the prediction (mm3/s)");
  sub->add_option("--reference-flow", args->reference_flow_mm3_s, "Flow at which relative_tau is 1 (mm3/s)")->capture_default_str();
  sub->add_option("--pressure-model", args->pressure_model, "boles, bellini, power-law or hagen-poiseuille")->capture_default_str();
  add_output_options(sub, args->output);
  sub->footer(
      "Examples:\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --json\n"
      "  tunekit rheo melt.csv --model cross --shift arrhenius --tts\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --power-law-window 600:950 \\\n"
      "      --power-law-at 390 --power-law-at 405 --power-law-at 450\n"
      "  tunekit rheo datasets/rheology/peek_cross_wlf_synthetic.csv --model cross-wlf --nozzle-d 0.6 --nozzle-l 4 \\\n"
      "      --cone-angle 30 --entrance-D 5 --predict-at 405 --reference-flow 3 --json   # results.prediction\n"
      "  tunekit rheo abs.csv --model cross-wlf --fix D2_K=378.15 --require 'n<0.5'\n"
      "  tunekit rheo datasets/rheology/polyimidazole_melt_viscosity.csv --temperatures 300:350\n"
      "  tunekit rheo melt.csv --viscosity-unit mPa.s     # a viscosity column without a unit\n"
      "Intervals: linearised (Wald) where they hold, profile likelihood where a parameter is strongly\n"
      "correlated, near a bound or on a curved likelihood (params.X.ci95_method). With data at several\n"
      "temperatures results.superposition tests each temperature against the master curve and names\n"
      "the temperatures that do not superpose (a transition, a degraded sample).\n"
      "Parameters (SI): n, tau_star_Pa, D1_Pa_s, D2_K, D3_K_per_Pa, A1, A2_K (cross-wlf); eta0_Pa_s, K_Pa_s_n,\n"
      "lambda_s, a, eta_inf_Pa_s; shifts Ea_J_per_mol or C1, C2_K with T_ref_K.");
  sub->callback([args, &ctx] { set_exit_code(run_rheo(*args, ctx)); });
}

}  // namespace tunekit::cli
