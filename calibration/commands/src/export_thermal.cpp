#include "export_thermal.hpp"

#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/design/thermal_control.hpp"

namespace tunekit::calibration::export_thermal {
namespace {

/// --thermal-model P:C:R:A:F[:H].
ident::ThermalModel parse_thermal_model(const std::string& arg) {
  std::vector<double> v;
  std::size_t b = 0;
  for (;;) {
    const std::size_t e = arg.find(':', b);
    const std::string part = arg.substr(b, e == std::string::npos ? std::string::npos : e - b);
    char* end = nullptr;
    const double x = std::strtod(part.c_str(), &end);
    if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(x))
      throw InputError(
          fmt::format("--thermal-model takes P:C:R:A:F[:H] numbers (W, J/K, 1/s, W/K, W/K, J/(K mm)), e.g. "
                      "40:16.7:0.22:0.068:0.097:0.0056; '{}' is not a number",
                      part));
    v.push_back(x);
    if (e == std::string::npos) break;
    b = e + 1;
  }
  if (v.size() != 5 && v.size() != 6)
    throw InputError(fmt::format("--thermal-model takes 5 or 6 values P:C:R:A:F[:H], not {} ('{}')", v.size(), arg));
  ident::ThermalModel m;
  m.heater_power_w = v[0];
  m.block_heat_capacity_j_per_k = v[1];
  m.sensor_responsiveness_per_s = v[2];
  m.ambient_transfer_w_per_k = v[3];
  m.fan_transfer_w_per_k = v[4];
  if (v.size() == 6) m.filament_heat_capacity_j_per_k_mm = v[5];
  return m;
}

}  // namespace

std::optional<firmware::ThermalExport> thermal_settings(const ExportOptions& a, const DesignInputs& d) {
  if (a.no_thermal) {
    if (!a.thermal_model.empty()) throw InputError("--thermal-model and --no-thermal contradict each other");
    return std::nullopt;
  }
  if (!a.thermal_model.empty() && d.thermal)
    throw InputError(
        fmt::format("--thermal-model and the thermal results {} both give the model: give one", d.thermal->origin));
  if (a.thermal_model.empty() && !d.thermal) return std::nullopt;
  firmware::ThermalExport t;
  t.model = d.thermal ? d.thermal->model : parse_thermal_model(a.thermal_model);
  t.pid.loop_delay_s = a.thermal_loop_delay;
  t.kalico_pid = a.kalico_pid;
  t.rrf_heater = a.heater;
  return t;
}

nlohmann::json thermal_results_json(firmware::ExportFirmware fw, const firmware::ThermalExport& t) {
  const auto& m = t.model;
  nlohmann::json j = {{"model",
                       {{"heater_power_w", m.heater_power_w},
                        {"block_heat_capacity_j_per_k", m.block_heat_capacity_j_per_k},
                        {"sensor_responsiveness_per_s", m.sensor_responsiveness_per_s},
                        {"ambient_transfer_w_per_k", m.ambient_transfer_w_per_k},
                        {"fan_transfer_w_per_k", m.fan_transfer_w_per_k},
                        {"filament_heat_capacity_j_per_k_mm", m.filament_heat_capacity_j_per_k_mm}}}};
  using firmware::ExportFirmware;
  if (fw == ExportFirmware::klipper || (fw == ExportFirmware::kalico && t.kalico_pid)) {
    const auto pid = design::design_thermal_pid(m, t.pid);
    const auto k = design::klipper_pid_gains(pid);
    j["pid"] = {{"rule", pid.rule},
                {"kp_per_k", pid.kp_per_k},
                {"ki_per_k_s", pid.ki_per_k_s},
                {"kd_s_per_k", pid.kd_s_per_k},
                {"pid_kp", k.kp},
                {"pid_ki", k.ki},
                {"pid_kd", k.kd},
                {"gain_margin", pid.gain_margin},
                {"phase_margin_deg", pid.phase_margin_deg},
                {"max_sensitivity", pid.max_sensitivity}};
  }
  if (fw == ExportFirmware::rrf) {
    const auto v = firmware::rrf_m307_values(t);
    j["m307"] = {{"H", t.rrf_heater}, {"R", v.r}, {"K", v.k}, {"D", v.d}, {"E", v.e}};
  }
  if (fw == ExportFirmware::marlin) j["m306"] = firmware::marlin_m306_gcode(t, 0);
  return j;
}

}  // namespace tunekit::calibration::export_thermal
