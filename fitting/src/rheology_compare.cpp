// Comparing viscosity models on the same data by AIC (Akaike weights); the winner gets its
// profile-likelihood intervals.
#include <algorithm>
#include <cmath>

#include "rheology_fit_detail.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/rheology_fit.hpp"

namespace tunekit::fitting {

using rheology_detail::finish_viscosity_fit;
using rheology_detail::kInf;
using rheology_detail::solve_viscosity;
using rheology_detail::strf;
using rheology_detail::viscosity_problem_for;

namespace {

// Relative difference of two AICs below which they tie (rounding of the residual sums).
constexpr double kAicTie = 1e-9;

}  // namespace

std::vector<ViscosityFitOptions> default_candidates(const RheologyData& data, const ViscosityFitOptions& base) {
  std::vector<ViscosityFitOptions> c;
  const bool multi = data.temperature_levels_K().size() > 1;
  for (auto m :
       {ViscosityModel::newtonian, ViscosityModel::power_law, ViscosityModel::cross, ViscosityModel::carreau_yasuda}) {
    ViscosityFitOptions o = base;
    o.fixed.clear();
    o.free.clear();
    o.model = m;
    o.shift = multi ? TemperatureShift::arrhenius : TemperatureShift::none;
    c.push_back(o);
    if (multi && m == ViscosityModel::cross) {
      o.shift = TemperatureShift::wlf;
      c.push_back(o);
    }
  }
  if (multi) {
    ViscosityFitOptions o = base;
    o.fixed.clear();
    o.free.clear();
    o.model = ViscosityModel::cross_wlf;
    o.shift = TemperatureShift::none;
    c.push_back(o);
  }
  return c;
}

ModelComparison compare_viscosity_models(const RheologyData& data, const std::vector<ViscosityFitOptions>& candidates,
                                         std::size_t also_finish) {
  ModelComparison c;
  double best = kInf;
  // The candidates are ranked by AIC, which needs no intervals: profile-likelihood intervals
  // (many refits each) are computed only for the winner, below with its own options.
  std::vector<FitResult> estimates;  // in solver coordinates, for the winner's intervals
  for (const auto& candidate : candidates) {
    ViscosityFitOptions o = candidate;
    o.profile_intervals = false;
    ModelComparisonEntry e;
    e.model = ViscositySpec{o.model, o.shift, {}}.name();
    FitResult fit;
    estimates.emplace_back();
    try {
      const auto vp = viscosity_problem_for(data, o);
      estimates.back() = solve_viscosity(*vp, o);
      fit = finish_viscosity_fit(data, o, *vp, estimates.back());
      e.ok = true;
      e.num_parameters = fit.diagnostics.num_parameters;
      e.aic = fit.diagnostics.aic;
      e.bic = fit.diagnostics.bic;
      e.rms_ln = fit.diagnostics.rms;
      if (!std::isfinite(e.aic)) {
        e.ok = false;
        e.error = strf("fitted, but its AIC is not finite (rss %g)", fit.diagnostics.rss);
      }
    } catch (const Error& err) {
      e.error = err.message();
    } catch (const std::exception& err) {
      e.error = err.what();
    }
    if (!e.ok && e.error.empty()) e.error = "the fit failed without giving a reason";
    if (!e.ok) fit = FitResult{};
    if (e.ok) best = std::min(best, e.aic);
    c.entries.push_back(e);
    c.fits.push_back(fit);
  }
  // The winner: the first candidate within rounding of the lowest AIC. Equivalent models (Cross
  // with a WLF shift and Cross-WLF without a pressure term) tie, and the tie must not be broken
  // by the last digits of two solvers' paths.
  for (const auto& e : c.entries)
    if (e.ok && e.aic <= best + kAicTie * std::max(1.0, std::abs(best))) {
      c.best = e.model;
      break;
    }
  std::size_t winner = candidates.size();
  for (std::size_t i = 0; i < c.entries.size() && winner == candidates.size(); ++i)
    if (c.entries[i].model == c.best) winner = i;
  for (std::size_t i = 0; i < c.entries.size(); ++i)
    if ((i == winner || i == also_finish) && c.entries[i].ok && candidates[i].profile_intervals) {
      // The estimate is the one the candidate's own fit would find (the same problem and
      // search): only its intervals are added, on that estimate.
      try {
        const auto vp = viscosity_problem_for(data, candidates[i]);
        c.fits[i] = finish_viscosity_fit(data, candidates[i], *vp, estimates[i]);
      } catch (const Error&) {
        // Keep the fit without profile intervals (its linearised intervals stand).
      }
    }
  double wsum = 0;
  for (auto& e : c.entries)
    if (e.ok) {
      e.delta_aic = e.aic - best;
      wsum += std::exp(-0.5 * e.delta_aic);
    }
  for (auto& e : c.entries)
    if (e.ok) e.akaike_weight = std::exp(-0.5 * e.delta_aic) / wsum;
  return c;
}

nlohmann::json to_json(const ModelComparison& c) {
  nlohmann::json j;
  j["criterion"] = "AIC on ln(viscosity) residuals (n ln(rss/n) + 2k)";
  j["best"] = c.best;
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& e : c.entries) {
    nlohmann::json x{{"model", e.model}, {"ok", e.ok}};
    if (e.ok) {
      x["num_parameters"] = e.num_parameters;
      x["aic"] = e.aic;
      x["bic"] = e.bic;
      x["delta_aic"] = e.delta_aic;
      x["akaike_weight"] = e.akaike_weight;
      x["rms_ln_viscosity"] = e.rms_ln;
    } else {
      x["error"] = e.error;
    }
    arr.push_back(x);
  }
  j["models"] = arr;
  return j;
}

}  // namespace tunekit::fitting
