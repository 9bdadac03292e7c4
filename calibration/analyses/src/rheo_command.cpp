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

#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/row_limit.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/rheology_fit.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/liquefier_prediction.hpp"
#include "tunekit/formats/rheology_data.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {
namespace {

using fitting::kNaN;

std::pair<double, double> rheo_parse_window(const std::string& s) {
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
    return InputError("--temperatures: expected LO:HI in degC, e.g. 300:350 (either side may be empty), got '" + s +
                      "'");
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

// The requested model's fit options: --fix/--free, the reference temperature, the model and
// its temperature shift (auto: Arrhenius for data at several temperatures). InputError for
// options that contradict each other.
fitting::ViscosityFitOptions primary_fit_options(const RheoOptions& a, const formats::RheologyCsvOptions& co,
                                                 bool multi) {
  fitting::ViscosityFitOptions primary;
  primary.fixed = parse_fixes(a.fix);
  primary.free = a.free;
  primary.T_ref_K = std::isfinite(a.t_ref_degc) ? a.t_ref_degc + co.kelvin_offset : kNaN;
  const bool auto_model = a.model == "auto";
  if (!auto_model) primary.model = fitting::parse_viscosity_model(a.model);
  if (a.shift == "auto")
    primary.shift = (multi && primary.model != fitting::ViscosityModel::cross_wlf)
                        ? fitting::TemperatureShift::arrhenius
                        : fitting::TemperatureShift::none;
  else primary.shift = fitting::parse_temperature_shift(a.shift);
  if (primary.model == fitting::ViscosityModel::cross_wlf && primary.shift != fitting::TemperatureShift::none)
    throw InputError("--shift: cross-wlf carries its own (WLF) temperature dependence; leave --shift at auto or none");
  if (auto_model && (!a.fix.empty() || !a.free.empty()))
    throw InputError("--fix/--free name parameters of one model; choose it with --model");
  if (auto_model && !a.compare)
    throw InputError("--model auto picks the best model by AIC; it cannot be combined with --no-compare");
  return primary;
}

// The fit reported: the requested model's (fitted once, as the comparison's first), or with
// --model auto the comparison's best; the comparison into o.comparison.
void fit_viscosity_models(RheoOutcome& o, const fitting::RheologyData& data,
                          const fitting::ViscosityFitOptions& primary, const RheoOptions& a) {
  const bool auto_model = a.model == "auto";
  fitting::FitResult& fit = o.fit;
  if (auto_model || !!a.compare) {
    auto cands = fitting::default_candidates(data, primary);
    if (!auto_model) {
      // The requested configuration replaces its default twin (it may carry --fix/--free).
      const std::string want = fitting::ViscositySpec{primary.model, primary.shift, {}}.name();
      cands.erase(std::remove_if(cands.begin(), cands.end(),
                                 [&](const auto& c) {
                                   return fitting::ViscositySpec{c.model, c.shift, {}}.name() == want;
                                 }),
                  cands.end());
      cands.insert(cands.begin(), primary);
    }
    // The requested model's fit, intervals included, is the comparison's first: fitted once.
    const auto cmp = fitting::compare_viscosity_models(data, cands, auto_model ? cands.size() : 0);
    if (!auto_model) {
      if (cmp.entries.front().ok) fit = cmp.fits.front();
      else fit = fitting::fit_viscosity(data, primary);  // throws with the reason it cannot be fitted
    }
    o.comparison = cmp;
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
}

// Do the temperatures superpose? A transition or a degraded sample shows here, and a
// temperature model fitted across it describes neither side. Warnings name the temperatures off
// the master curve and the reversals; with --tts a failed check is an error.
void check_temperatures_superpose(RheoOutcome& o, const fitting::RheologyData& data, double T_ref_K,
                                  const formats::RheologyCsvOptions& co, const RheoOptions& a) {
  try {
    const auto sc = fitting::check_superposition(data, T_ref_K);
    o.superposition = sc;
    const auto degc = [&](double K) {
      return fmt::format("{:g} degC", std::round((K - co.kelvin_offset) * 100) / 100);
    };
    std::string off;
    for (const auto& l : sc.levels)
      if (!l.on_master_curve) off += (off.empty() ? "" : ", ") + degc(l.temperature_K);
    if (!off.empty())
      o.warnings.push_back(
          fmt::format("the curves at {} do not lie on the master curve of the other temperatures (F test, p < {:g}): "
                      "a transition, a degraded sample or a change of mechanism; one temperature-shift model "
                      "cannot hold them (select a range with --temperatures)",
                      off, sc.alpha));
    for (const auto& r : sc.reversals)
      o.warnings.push_back(
          fmt::format("the viscosity rises between {} and {} (shift factor x{:.3g}): a transition between these "
                      "temperatures (e.g. a liquid-crystalline melt turning isotropic) or curves of different samples; "
                      "fit each side on its own with --temperatures",
                      degc(r.lower_K), degc(r.upper_K), r.ratio));
  } catch (const Error& e) {
    if (a.tts) throw;
    o.warnings.push_back("superposition check not done: " + e.message());
  }
}

}  // namespace

RheoOutcome compute_rheo(const RheoOptions& a) {
  RheoOutcome o;
  o.options = a;
  const std::string bytes = read_file_bytes(a.file);
  o.input_sha256 = sha256_hex(bytes);
  o.input_size_bytes = bytes.size();
  formats::RheologyCsvOptions co = a.csv;
  if (!co.viscosity_column.empty() && !co.stress_column.empty())
    throw InputError("give --viscosity or --shear-stress, not both");
  if (!a.temperatures.empty())
    std::tie(co.temperature_min_degC, co.temperature_max_degC) = parse_temperature_range(a.temperatures);
  if (!(co.kelvin_offset == fitting::kKelvinOffset || co.kelvin_offset == fitting::kKelvinOffsetThesis))
    throw InputError("--kelvin-offset must be 273.15 (SI) or 273 (Holtrup's (2019) code)");
  require_line_limit(bytes, a.max_rows, "--max-rows", a.file);
  const auto table = formats::parse_rheology_csv(bytes, a.file, co);
  const auto& data = table.data;
  require_row_limit(data.size(), a.max_rows, "--max-rows", a.file);
  const auto levels = data.temperature_levels_K();
  const bool multi = levels.size() > 1;

  const fitting::ViscosityFitOptions primary = primary_fit_options(a, co, multi);

  o.num_points = data.size();
  o.temperatures_K = levels;
  for (const auto& n : table.notes) o.warnings.push_back(a.file + ": " + n);
  o.warnings.insert(o.warnings.end(), table.warnings.begin(), table.warnings.end());

  fit_viscosity_models(o, data, primary, a);
  const fitting::FitResult& fit = o.fit;
  const auto spec = fitting::spec_from_fit(fit);

  o.warnings.insert(o.warnings.end(), fit.warnings.begin(), fit.warnings.end());

  const double T_mid = levels[(levels.size() - 1) / 2];
  if (!a.power_law_window.empty()) {
    o.power_law_window_1_s = rheo_parse_window(a.power_law_window);
    std::vector<double> temps;
    for (double c : a.power_law_at_degc) temps.push_back(c + co.kelvin_offset);
    if (temps.empty()) temps = levels;
    for (double T : temps)
      o.power_laws.push_back({T, fitting::fit_power_law_window(spec, T, o.power_law_window_1_s.first,
                                                               o.power_law_window_1_s.second, a.power_law_points)});
  }
  if (a.tts && !multi) throw InputError("--tts needs data at two or more temperatures", a.file);
  if (multi) check_temperatures_superpose(o, data, primary.T_ref_K, co, a);
  if (a.predict) {
    ident::LiquefierPredictionOptions po = a.prediction;
    po.temperature_K = std::isfinite(a.predict_at_degc) ? a.predict_at_degc + co.kelvin_offset : T_mid;
    o.prediction = ident::predict_liquefier(spec, po);
  }
  return o;
}
namespace {
// The geometry as the user gave it (mm, degrees), without the last-digit noise of the m/rad round trip.
double rheo_user_units(double v) { return std::stod(fmt::format("{:.12g}", v)); }
}  // namespace

Envelope to_envelope(const RheoOutcome& o) {
  const RheoOptions& a = o.options;
  Envelope env("rheo");
  env.add_input_digest(a.file, o.input_sha256, o.input_size_bytes);
  const auto& g = a.prediction.geometry;
  env.set_options({{"model", a.model},
                   {"shift", a.shift},
                   {"kelvin_offset", a.csv.kelvin_offset},
                   {"viscosity_unit", a.csv.viscosity_unit},
                   {"temperatures_degC", a.temperatures},
                   {"fix", a.fix},
                   {"free", a.free},
                   {"compare", a.compare},
                   {"tts", a.tts},
                   {"power_law_window", a.power_law_window},
                   {"power_law_points", a.power_law_points},
                   {"nozzle_d_mm", a.predict ? nlohmann::json(rheo_user_units(g.d_m * 1e3)) : nlohmann::json()},
                   {"nozzle_l_mm", rheo_user_units(g.l_m * 1e3)},
                   {"cone_angle_deg", rheo_user_units(g.cone_half_angle_rad * 180.0 / std::numbers::pi)},
                   {"entrance_D_mm", rheo_user_units(g.D_m * 1e3)},
                   {"reference_flow_mm3_s", a.prediction.reference_flow_mm3_s},
                   {"pressure_model", fitting::to_string(a.prediction.model)},
                   {"columns",
                    {{"shear_rate", a.csv.shear_rate_column},
                     {"viscosity", a.csv.viscosity_column},
                     {"shear_stress", a.csv.stress_column},
                     {"temperature", a.csv.temperature_column},
                     {"pressure", a.csv.pressure_column}}},
                   {"units",
                    {{"viscosity", a.csv.viscosity_unit},
                     {"shear_stress", a.csv.stress_unit},
                     {"temperature", a.csv.temperature_unit}}}});
  for (const auto& w : o.warnings) env.warn(w);
  auto& res = env.results();
  res = fitting::to_json(o.fit);
  res["temperatures_K"] = o.temperatures_K;
  res["num_points"] = o.num_points;
  res["kelvin_offset"] = a.csv.kelvin_offset;
  if (o.comparison) res["model_comparison"] = fitting::to_json(*o.comparison);
  if (!a.power_law_window.empty()) {
    nlohmann::json fits = nlohmann::json::array();
    for (const auto& pl : o.power_laws) {
      auto j = fitting::to_json(pl.fit);
      j["temperature_K"] = pl.temperature_K;
      fits.push_back(j);
    }
    res["power_law"] = {{"window_1_s", {o.power_law_window_1_s.first, o.power_law_window_1_s.second}},
                        {"points", a.power_law_points},
                        {"spacing", "log"},
                        {"fits", fits}};
  }
  if (o.superposition) {
    res["superposition"] = fitting::to_json(*o.superposition);
    if (a.tts) res["tts"] = fitting::to_json(o.superposition->tts);
  }
  if (auto corr = fitting::correlation_json(o.fit); !corr.is_null()) res["correlation"] = corr;
  if (o.prediction) res["prediction"] = ident::to_json(*o.prediction);
  return env;
}

namespace {

// The shift factor of each temperature of a superposition check, and whether it is on the curve.
void print_superposition(const fitting::SuperpositionCheck& c, std::ostream& os) {
  for (const auto& l : c.levels)
    os << fmt::format("  a_T at {:.2f} K: {:.4g} [{:.4g}, {:.4g}]{}\n", l.temperature_K, l.shift_factor, l.shift_lo,
                      l.shift_hi, l.on_master_curve ? "" : "  NOT on the master curve");
}

void print_comparison(const fitting::ModelComparison& c, std::ostream& os) {
  os << "  model comparison (AIC):\n";
  for (const auto& e : c.entries) {
    if (e.ok)
      os << fmt::format("    {:<26} k={} dAIC {:8.2f} weight {:.3f}\n", e.model, e.num_parameters, e.delta_aic,
                        e.akaike_weight);
    else os << fmt::format("    {:<26} not fitted: {}\n", e.model, e.error);
  }
}

void print_prediction(const ident::LiquefierPrediction& p, std::ostream& os) {
  os << fmt::format("  liquefier at {:.2f} K ({}): flow mm3/s, dP MPa, dP/dQ Pa.s/mm3, relative tau\n", p.temperature_K,
                    p.pressure_model);
  for (std::size_t i = 0; i < p.flow_mm3_s.size(); ++i)
    os << fmt::format("    {:8.3g} {:10.4g} {:12.5g} {:8.4f}\n", p.flow_mm3_s[i], p.pressure_drop_Pa[i] * 1e-6,
                      p.dP_dQ_Pa_s_per_mm3[i], p.relative_tau[i]);
}

}  // namespace

void print_text(const RheoOutcome& o, std::ostream& os) {
  const auto& fit = o.fit;
  os << fmt::format("{}: {} points at {} temperature(s); model {}\n", o.options.file, o.num_points,
                    o.temperatures_K.size(), fit.model);
  for (const auto& p : fit.params) {
    if (p.fixed) os << fmt::format("  {:<14} {:>12.6g} {:<8} (held)\n", p.name, p.value, p.unit);
    else
      os << fmt::format("  {:<14} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]{}\n", p.name, p.value, p.unit, p.ci95_lo,
                        p.ci95_hi, p.ci95_method == "profile-likelihood" ? " (profile likelihood)" : "");
  }
  for (const auto& p : fit.derived)
    os << fmt::format("  {:<26} {:>12.6g} {:<8} 95% [{:.6g}, {:.6g}]\n", p.name, p.value, p.unit, p.ci95_lo, p.ci95_hi);
  if (o.superposition) print_superposition(*o.superposition, os);
  os << fmt::format("  rms(ln eta) {:.4g}, R2 {:.5f}, AIC {:.2f}\n", fit.diagnostics.rms, fit.diagnostics.r2,
                    fit.diagnostics.aic);
  if (o.comparison) print_comparison(*o.comparison, os);
  for (const auto& pl : o.power_laws)
    os << fmt::format("  power law at {:.2f} K: K {:.6g} Pa.s^n, n {:.5f}\n", pl.temperature_K,
                      pl.fit.param("K_Pa_s_n").value, pl.fit.param("n").value);
  if (o.prediction) print_prediction(*o.prediction, os);
}

}  // namespace tunekit::calibration
