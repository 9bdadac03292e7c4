#include "tunekit/fitting/fit_result.hpp"

#include <algorithm>
#include <cmath>
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
  if (!p.ci95_method.empty()) j["ci95_method"] = p.ci95_method;
  return j;
}

nlohmann::json to_json(const Diagnostics& d) {
  return {{"converged", d.converged},
          {"n", d.num_observations},
          {"k", d.num_parameters},
          {"iterations", d.iterations},
          {"rss", d.rss},
          {"rms", d.rms},
          {"r2", d.r2},
          {"aic", d.aic},
          {"bic", d.bic},
          {"whiteness_p", d.whiteness_p},
          {"whiteness_lags", d.whiteness_lags},
          {"solver", d.solver}};
}

nlohmann::json to_json(const FitResult& r) {
  nlohmann::json params = nlohmann::json::object();
  for (const auto& p : r.params) params[p.name] = to_json(p);
  nlohmann::json j{{"model", r.model}, {"params", params}, {"diagnostics", to_json(r.diagnostics)}};
  if (!r.derived.empty()) {
    nlohmann::json d = nlohmann::json::object();
    for (const auto& p : r.derived) d[p.name] = to_json(p);
    j["derived"] = d;
  }
  if (!r.warnings.empty()) j["warnings"] = r.warnings;
  return j;
}

nlohmann::json correlation_json(const FitResult& r) {
  const std::size_t n = r.params.size();
  if (r.covariance.size() != n * n) return nullptr;
  std::vector<std::size_t> fr;
  nlohmann::json names = nlohmann::json::array();
  for (std::size_t i = 0; i < n; ++i)
    if (!r.params[i].fixed) fr.push_back(i), names.push_back(r.params[i].name);
  nlohmann::json m = nlohmann::json::array();
  for (auto i : fr) {
    nlohmann::json row = nlohmann::json::array();
    for (auto j : fr) {
      const double d = std::sqrt(r.covariance[i * n + i] * r.covariance[j * n + j]);
      const double c = d > 0 ? r.covariance[i * n + j] / d : (i == j ? 1.0 : 0.0);
      row.push_back(std::clamp(c, -1.0, 1.0));
    }
    m.push_back(row);
  }
  return {{"parameters", names}, {"matrix", m}};
}

}  // namespace tunekit::fitting
