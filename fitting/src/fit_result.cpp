#include "tunekit/fitting/fit_result.hpp"

#include <stdexcept>

namespace tunekit::fitting {

const Param& FitResult::param(const std::string& name) const {
  for (const auto& p : params)
    if (p.name == name) return p;
  throw std::out_of_range("no parameter '" + name + "' in model " + model);
}

nlohmann::json to_json(const Param& p) {
  nlohmann::json j;
  j["value"] = p.value;
  j["stderr"] = p.std_error;
  j["ci95"] = {p.ci95_lo, p.ci95_hi};
  j["unit"] = p.unit;
  if (p.fixed) j["fixed"] = true;
  return j;
}

nlohmann::json to_json(const Diagnostics& d) {
  return {{"converged", d.converged},     {"n", d.num_observations},
          {"k", d.num_parameters},        {"iterations", d.iterations},
          {"rss", d.rss},                 {"rms", d.rms},
          {"r2", d.r2},                   {"aic", d.aic},
          {"bic", d.bic},                 {"whiteness_p", d.whiteness_p},
          {"whiteness_lags", d.whiteness_lags}, {"solver", d.solver}};
}

nlohmann::json to_json(const FitResult& r) {
  nlohmann::json params = nlohmann::json::object();
  for (const auto& p : r.params) params[p.name] = to_json(p);
  nlohmann::json j{{"model", r.model}, {"params", params}, {"diagnostics", to_json(r.diagnostics)}};
  if (!r.warnings.empty()) j["warnings"] = r.warnings;
  return j;
}

}  // namespace tunekit::fitting
