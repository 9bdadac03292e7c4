// Builds an experiment: the protocol's parameters filled in and checked, then the G-code of its
// family (experiments_liquefier.cpp, experiments_axis.cpp, experiments_print.cpp).
#include "tunekit/protocols/experiments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/text.hpp"

#include "tunekit/core/error.hpp"
#include "tunekit/protocols/chirp_plan.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/protocols/camera_prints.hpp"
#include "tunekit/protocols/coverage_planner.hpp"
#include "tunekit/protocols/flow_sweep_plan.hpp"
#include "tunekit/machine/gcode.hpp"
#include "tunekit/machine/trajectory.hpp"

#include "experiment_gcode.hpp"
#include "machine_defaults.hpp"

namespace tunekit::protocols {

nlohmann::json Experiment::to_json() const {
  nlohmann::json j;
  j["protocol"] = protocol;
  if (!axis.empty()) j["axis"] = axis;
  j["params"] = params;
  j["sensors"] = sensors;
  j["gcode_lines"] = gcode.size();
  j["estimated_duration_s"] = estimated_duration_s;
  j["excitation"] = excitation;
  return j;
}

namespace {

void check_param_domain(const std::string& protocol, const ProtocolParam& prm, double v) {
  if (!std::isfinite(v))
    throw InputError(fmt::format("{} parameter {} must be a finite number, not {}", protocol, prm.name, v));
  const char* why = nullptr;
  switch (prm.domain) {
    case ParamDomain::positive:
      if (!(v > 0)) why = "must be positive";
      break;
    case ParamDomain::non_negative:
      if (v < 0 || std::signbit(v)) why = "must not be negative";
      break;
    case ParamDomain::count:
      if (!(v >= 1) || v != std::floor(v)) why = "must be a whole number >= 1";
      break;
    case ParamDomain::any: break;
  }
  if (!why && std::abs(v) > prm.max_value) why = "is beyond its plausible range";
  if (why) {
    const std::string lower = prm.domain == ParamDomain::any        ? fmt::format("-{:g}", prm.max_value)
                              : prm.domain == ParamDomain::positive ? std::string("above 0")
                              : prm.domain == ParamDomain::count    ? std::string("1")
                                                                    : std::string("0");
    throw InputError(fmt::format("{} parameter {} {} (accepted: {} to {:g}{}), not {:g}", protocol, prm.name, why,
                                 lower, prm.max_value, prm.unit.empty() ? "" : " " + prm.unit, v));
  }
}

}  // namespace

Experiment build_experiment(const std::string& protocol, const std::map<std::string, double>& overrides,
                            const std::string& axis_in, const machine::MachineProfile& profile,
                            const firmware::Dialect& d, const ProtocolLimits& limits) {
  const auto& spec = protocol_spec(protocol);
  Experiment e;
  e.protocol = protocol;
  e.sensors = spec.sensors;
  for (const auto& prm : spec.params) e.params[prm.name] = prm.default_value;
  for (const auto& [k, v] : overrides) {
    if (!e.params.count(k)) {
      std::string known;
      for (const auto& prm : spec.params) known += (known.empty() ? "" : ", ") + prm.name;
      throw InputError(fmt::format("protocol {} has no parameter '{}' (parameters: {})", protocol, k, known));
    }
    e.params[k] = v;
  }
  // Every parameter in its domain (defaults that come from the machine are NaN until filled in).
  for (const auto& prm : spec.params)
    if (!(std::isnan(prm.default_value) && !overrides.count(prm.name)))
      check_param_domain(protocol, prm, e.params.at(prm.name));
  const experiment_gcode::ExperimentRequest request{spec.id, protocol, overrides, axis_in, profile, d, limits};
  // The defaults that come from the machine's limits, in their domains too (the positions stay
  // NaN: the builders put them at the middle of the travel).
  experiment_gcode::fill_machine_defaults(request, e);
  for (const auto& prm : spec.params)
    if (std::isnan(prm.default_value) && !overrides.count(prm.name) && !std::isnan(e.params.at(prm.name)))
      check_param_domain(protocol, prm, e.params.at(prm.name));
  auto& g = e.gcode;
  g.push_back(fmt::format("; tunekit {} on {}", protocol, core::comment_safe(profile.name)));
  if (spec.id == Protocol::heater_identify) experiment_gcode::build_thermal_experiment(request, e);
  else if (!experiment_gcode::build_liquefier_experiment(request, e) &&
           !experiment_gcode::build_axis_experiment(request, e))
    experiment_gcode::build_print_experiment(request, e);
  e.estimated_duration_s = estimate_gcode_duration_s(g);
  return e;
}

}  // namespace tunekit::protocols
