#include "tunekit/machine/klipper_settings.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace tunekit::machine {
namespace {

/// A number from an object, whether Klipper sent it as a number or (input_shaper) as a string.
double number(const nlohmann::json& obj, const std::string& key) {
  if (!obj.is_object() || !obj.contains(key)) return kNotReported;
  const auto& v = obj[key];
  if (v.is_number()) return v.get<double>();
  if (v.is_string()) {
    try {
      return std::stod(v.get<std::string>());
    } catch (const std::exception&) {
      return kNotReported;
    }
  }
  return kNotReported;
}

const nlohmann::json& member(const nlohmann::json& obj, const std::string& key) {
  static const nlohmann::json empty = nlohmann::json::object();
  return obj.is_object() && obj.contains(key) && obj[key].is_object() ? obj[key] : empty;
}

/// Lowers `value` to the firmware's when the firmware's is stricter; notes the change.
void stricter(double& value, double firmware_value, const std::string& what, const std::string& unit,
              std::vector<std::string>& notes) {
  if (!std::isfinite(firmware_value) || firmware_value <= 0) return;
  if (value > 0 && value <= firmware_value) return;
  notes.push_back(fmt::format("{}: {} {} (Klipper's; the profile's {} {} is not stricter)", what, firmware_value, unit,
                              value, unit));
  value = firmware_value;
}

}  // namespace

nlohmann::json klipper_settings_query() {
  return {
      {"objects", {{"configfile", nlohmann::json::array({"settings"})}, {"toolhead", nullptr}, {"extruder", nullptr}}}};
}

KlipperSettings parse_klipper_settings(const nlohmann::json& info, const nlohmann::json& query) {
  KlipperSettings k;
  if (info.is_object()) {
    k.state = info.value("state", "");
    k.state_message = info.value("state_message", "");
    if (info.contains("software_version") && info["software_version"].is_string())
      k.software_version = info["software_version"].get<std::string>();
  }
  const auto& status = member(query, "status");
  const auto& settings = member(member(status, "configfile"), "settings");
  const auto& toolhead = member(status, "toolhead");
  const auto& extruder = member(status, "extruder");
  const auto& printer_cfg = member(settings, "printer");
  const auto& extruder_cfg = member(settings, "extruder");
  // Live values first (SET_VELOCITY_LIMIT may have changed them), the configuration otherwise.
  auto live_or_config = [](const nlohmann::json& live, const nlohmann::json& cfg, const std::string& key) {
    const double v = number(live, key);
    return std::isfinite(v) ? v : number(cfg, key);
  };
  k.max_velocity_mm_s = live_or_config(toolhead, printer_cfg, "max_velocity");
  k.max_accel_mm_s2 = live_or_config(toolhead, printer_cfg, "max_accel");
  k.minimum_cruise_ratio = live_or_config(toolhead, printer_cfg, "minimum_cruise_ratio");
  k.square_corner_velocity_mm_s = live_or_config(toolhead, printer_cfg, "square_corner_velocity");
  k.max_extrude_only_velocity_mm_s = number(extruder_cfg, "max_extrude_only_velocity");
  k.max_extrude_only_accel_mm_s2 = number(extruder_cfg, "max_extrude_only_accel");
  k.max_extrude_only_distance_mm = number(extruder_cfg, "max_extrude_only_distance");
  k.pressure_advance_s = live_or_config(extruder, extruder_cfg, "pressure_advance");
  k.smooth_time_s = number(extruder, "smooth_time");
  if (!std::isfinite(k.smooth_time_s)) k.smooth_time_s = number(extruder_cfg, "pressure_advance_smooth_time");
  // [input_shaper]: shaper_type_<axis> falls back to shaper_type (default mzv), damping_ratio_<axis>
  // defaults to 0.1 (klippy/extras/input_shaper.py InputShaperParams).
  const auto& shaper_cfg = member(settings, "input_shaper");
  for (const std::string axis : {"x", "y"}) {
    const double freq = number(shaper_cfg, "shaper_freq_" + axis);
    if (!std::isfinite(freq) || freq <= 0) continue;
    std::string type = shaper_cfg.value("shaper_type_" + axis, shaper_cfg.value("shaper_type", std::string("mzv")));
    double zeta = number(shaper_cfg, "damping_ratio_" + axis);
    if (!std::isfinite(zeta)) zeta = 0.1;
    k.shaper[axis] = fmt::format("{}:{}:{}", type, freq, zeta);
  }
  return k;
}

MachineProfile with_klipper_settings(const MachineProfile& profile, const KlipperSettings& k,
                                     std::vector<std::string>& notes) {
  MachineProfile p = profile;
  stricter(p.extruder.max_velocity_mm_s, k.max_extrude_only_velocity_mm_s, "extruder feed limit", "mm/s", notes);
  stricter(p.extruder.max_accel_mm_s2, k.max_extrude_only_accel_mm_s2, "extruder acceleration limit", "mm/s^2", notes);
  stricter(p.extruder.max_extrude_only_distance_mm, k.max_extrude_only_distance_mm, "longest extrude-only move", "mm",
           notes);
  // The machine's own settings in force are what a test restores after it.
  if (std::isfinite(k.minimum_cruise_ratio) && k.minimum_cruise_ratio != p.state.minimum_cruise_ratio) {
    notes.push_back(fmt::format("minimum_cruise_ratio in force: {} (the profile says {})", k.minimum_cruise_ratio,
                                p.state.minimum_cruise_ratio));
    p.state.minimum_cruise_ratio = k.minimum_cruise_ratio;
  }
  if (k.shaper != p.state.shaper) {
    std::string desc;
    for (const auto& [axis, v] : k.shaper) desc += fmt::format("{}{} {}", desc.empty() ? "" : ", ", axis, v);
    notes.push_back(fmt::format("input shaper in force: {}", desc.empty() ? "none" : desc));
    p.state.shaper = k.shaper;
  }
  if (std::isfinite(k.max_accel_mm_s2) && k.max_accel_mm_s2 > 0) {
    if (k.max_accel_mm_s2 != p.print.max_accel_mm_s2)
      notes.push_back(
          fmt::format("acceleration in force: {} mm/s^2 (restored after a test; the profile's print "
                      "acceleration is {} mm/s^2)",
                      k.max_accel_mm_s2, p.print.max_accel_mm_s2));
    p.state.accel_in_force_mm_s2 = k.max_accel_mm_s2;
  }
  return p;
}

}  // namespace tunekit::machine
