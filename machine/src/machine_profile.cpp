#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/machine/profile_import.hpp"
#include "tunekit/machine/rrf_http.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

#include <algorithm>

#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "toml_depth.hpp"

namespace tunekit::machine {
namespace {

class Reader {
 public:
  Reader(const toml::table& root, std::string path) : root_(root), path_(std::move(path)) {}

  double positive(const toml::table& t, const std::string& section, const char* key, bool required,
                  double fallback) const {
    const auto* node = t.get(key);
    if (!node) {
      if (required) throw InputError(fmt::format("[{}] needs '{}'", section, key), path_);
      return fallback;
    }
    const auto v = node->value<double>();
    const std::string where = where_of(*node);
    if (!v) throw InputError(fmt::format("[{}] {} must be a number", section, key), where);
    if (!(*v > 0) || !std::isfinite(*v))
      throw InputError(fmt::format("[{}] {} must be positive, not {}", section, key, *v), where);
    return *v;
  }

  double number(const toml::table& t, const std::string& section, const char* key, double fallback) const {
    const auto* node = t.get(key);
    if (!node) return fallback;
    const auto v = node->value<double>();
    if (!v) throw InputError(fmt::format("[{}] {} must be a number", section, key), where_of(*node));
    if (!std::isfinite(*v))
      throw InputError(fmt::format("[{}] {} must be a finite number, not {}", section, key, *v), where_of(*node));
    return *v;
  }

  bool flag(const toml::table& t, const char* key, bool fallback) const {
    const auto* node = t.get(key);
    if (!node) return fallback;
    const auto v = node->value<bool>();
    if (!v) throw InputError(fmt::format("'{}' must be true or false", key), where_of(*node));
    return *v;
  }

  std::string text(const toml::table& t, const char* key, const std::string& fallback) const {
    const auto* node = t.get(key);
    if (!node) return fallback;
    const auto v = node->value<std::string>();
    if (!v || v->empty()) throw InputError(fmt::format("'{}' must be a non-empty string", key), where_of(*node));
    return *v;
  }

  const toml::table& section(const char* name, bool required) const {
    static const toml::table empty;
    const auto* t = root_.get_as<toml::table>(name);
    if (!t) {
      if (required) throw InputError(fmt::format("missing section [{}]", name), path_);
      return empty;
    }
    return *t;
  }

  std::string where_of(const toml::node& n) const {
    const auto& src = n.source();
    return src.begin.line > 0 ? source_location(path_, src.begin.line) : path_;
  }

 private:
  const toml::table& root_;
  std::string path_;
};

}  // namespace

double MachineProfile::filament_area_mm2() const {
  return std::numbers::pi / 4.0 * extruder.filament_diameter_mm * extruder.filament_diameter_mm;
}

double MachineProfile::line_area_mm2() const { return print.line_width_mm * print.layer_height_mm; }

const AxisLimits& MachineProfile::axis(const std::string& name) const {
  const auto it = axes.find(name);
  if (it == axes.end()) throw InputError(fmt::format("the machine profile has no axis '{}'", name), source_path);
  return it->second;
}

namespace {

// The physical ranges of a profile's limits (machine_profile.hpp, profile_limits).
constexpr double kMaxTravel_mm = profile_limits::kMaxTravel_mm;
constexpr double kMaxSpeed_mm_s = profile_limits::kMaxSpeed_mm_s;
constexpr double kMaxAccel_mm_s2 = profile_limits::kMaxAccel_mm_s2;
constexpr double kMaxHotend_c = profile_limits::kMaxHotend_c;
constexpr double kMaxBed_c = profile_limits::kMaxBed_c;
constexpr double kMaxFilament_mm = profile_limits::kMaxFilament_mm;
constexpr double kMaxFlow_mm3_s = profile_limits::kMaxFlow_mm3_s;
constexpr double kMaxSampleRate_hz = profile_limits::kMaxSampleRate_hz;

/// Every limit of the profile within its physical range (InputError naming the key otherwise).
void check_physical_ranges(const MachineProfile& p, const std::string& path) {
  const auto within = [&](double v, double hi, const std::string& key, const char* unit) {
    if (!(std::isfinite(v) && std::fabs(v) <= hi))
      throw InputError(
          fmt::format("{} = {} is beyond the physical range of a printer (at most {} {})", key, v, hi, unit), path);
  };
  for (const auto& [name, a] : p.axes) {
    within(a.min_mm, kMaxTravel_mm, "[axes." + name + "] min_mm", "mm");
    within(a.max_mm, kMaxTravel_mm, "[axes." + name + "] max_mm", "mm");
    within(a.max_velocity_mm_s, kMaxSpeed_mm_s, "[axes." + name + "] max_velocity_mm_s", "mm/s");
    within(a.max_accel_mm_s2, kMaxAccel_mm_s2, "[axes." + name + "] max_accel_mm_s2", "mm/s^2");
  }
  within(p.extruder.filament_diameter_mm, kMaxFilament_mm, "[extruder] filament_diameter_mm", "mm");
  within(p.extruder.nozzle_diameter_mm, kMaxFilament_mm, "[extruder] nozzle_diameter_mm", "mm");
  within(p.extruder.max_flow_mm3_s, kMaxFlow_mm3_s, "[extruder] max_flow_mm3_s", "mm^3/s");
  within(p.extruder.max_velocity_mm_s, kMaxSpeed_mm_s, "[extruder] max_velocity_mm_s", "mm/s");
  within(p.extruder.max_accel_mm_s2, kMaxAccel_mm_s2, "[extruder] max_accel_mm_s2", "mm/s^2");
  within(p.extruder.max_extrude_only_distance_mm, kMaxTravel_mm, "[extruder] max_extrude_only_distance_mm", "mm");
  within(p.print.max_accel_mm_s2, kMaxAccel_mm_s2, "[print] max_accel_mm_s2", "mm/s^2");
  within(p.print.speed_mm_s, kMaxSpeed_mm_s, "[print] speed_mm_s", "mm/s");
  within(p.print.line_width_mm, kMaxFilament_mm, "[print] line_width_mm", "mm");
  within(p.print.layer_height_mm, kMaxFilament_mm, "[print] layer_height_mm", "mm");
  within(p.temperature.hotend_max_c, kMaxHotend_c, "[temperature] hotend_max_c", "degC");
  within(p.temperature.bed_max_c, kMaxBed_c, "[temperature] bed_max_c", "degC");
  within(p.sensors.accelerometer_rate_hz, kMaxSampleRate_hz, "[sensors] accelerometer_rate_hz", "Hz");
}

}  // namespace

namespace {

// [axes.NAME]: each axis' travel, speed and acceleration limits.
void read_axes(Reader& r, MachineProfile& p, const std::string& path) {
  const auto& axes = r.section("axes", true);
  for (const auto& [key, node] : axes) {
    const auto* t = node.as_table();
    const std::string name(key.str());
    if (!t) throw InputError(fmt::format("[axes.{}] must be a table", name), r.where_of(node));
    AxisLimits a;
    const std::string sec = "axes." + name;
    a.min_mm = r.number(*t, sec, "min_mm", 0);
    a.max_mm = r.number(*t, sec, "max_mm", 0);
    if (!(a.max_mm > a.min_mm))
      throw InputError(fmt::format("[{}] max_mm ({}) must exceed min_mm ({})", sec, a.max_mm, a.min_mm),
                       r.where_of(node));
    a.max_velocity_mm_s = r.positive(*t, sec, "max_velocity_mm_s", true, 0);
    a.max_accel_mm_s2 = r.positive(*t, sec, "max_accel_mm_s2", true, 0);
    p.axes[name] = a;
  }
  if (p.axes.empty()) throw InputError("[axes] lists no axis", path);
}

// [sensors]: which sensors the machine has and what they are called.
void read_sensors(Reader& r, MachineProfile& p) {
  const auto& s = r.section("sensors", false);
  // accelerometer = true (an ADXL345) or the chip's name as Klipper's config section names it.
  if (const auto* node = s.get("accelerometer"); node != nullptr && node->is_string()) {
    p.sensors.accelerometer = true;
    p.sensors.accelerometer_chip = *node->value<std::string>();
    if (!is_klipper_accelerometer_chip(p.sensors.accelerometer_chip))
      throw InputError(fmt::format("[sensors] accelerometer '{}' is not a chip Klipper reads ({})",
                                   p.sensors.accelerometer_chip, klipper_accelerometer_chips()),
                       r.where_of(*node));
  } else {
    p.sensors.accelerometer = r.flag(s, "accelerometer", false);
  }
  p.sensors.accelerometer_name = r.text(s, "accelerometer_name", p.sensors.accelerometer_chip);
  p.sensors.load_cell = r.flag(s, "load_cell", false);
  p.sensors.load_cell_name = r.text(s, "load_cell_name", "load_cell");
  p.sensors.filament_encoder = r.flag(s, "filament_encoder", false);
  p.sensors.camera = r.flag(s, "camera", false);
  p.sensors.accelerometer_rate_hz = r.positive(s, "sensors", "accelerometer_rate_hz", false, 3200);
}

// [network]: the firmware's HTTP address (checked) and password.
void read_network(Reader& r, MachineProfile& p, const std::string& path) {
  const auto& net = r.section("network", false);
  p.http_address = r.text(net, "http", "");
  if (!p.http_address.empty()) {
    try {
      (void)parse_http_address(p.http_address);
    } catch (const InputError& e) {
      throw InputError(e.message(), path);
    }
  }
  p.http_password = r.text(net, "password", "");  // never echoed: see rrf_http.hpp
}

// [firmware_state]: what the firmware runs with now (shapers, M493 report, planner settings).
void read_firmware_state(Reader& r, MachineProfile& p) {
  const auto& fs = r.section("firmware_state", false);
  for (const char* axis : {"x", "y"}) {
    const std::string key = std::string("shaper_") + axis;
    if (const auto* node = fs.get(key)) {
      const auto v = node->value<std::string>();
      if (!v || std::count(v->begin(), v->end(), ':') != 2)
        throw InputError(
            fmt::format("[firmware_state] {} must be \"type:freq_hz:damping\", e.g. \"mzv:48.6:0.1\"", key),
            r.where_of(*node));
      p.state.shaper[axis] = *v;
    }
  }
  auto& st = p.state;
  if (const auto* node = fs.get("m493_report")) {
    const auto* lines = node->as_array();
    if (lines)
      for (const auto& l : *lines)
        if (const auto v = l.value<std::string>()) st.m493_report.push_back(*v);
    if (!lines || st.m493_report.size() != lines->size())
      throw InputError(
          "[firmware_state] m493_report must be the printer's M493 answer as a list of lines, e.g. "
          "[\"Fixed-Time Motion enabled (X=ZV ; Y=MZV)\", \"X static shaper frequency: 40.00Hz\"]",
          r.where_of(*node));
  }
  if (const auto* node = fs.get("minimum_cruise_ratio")) {
    const auto v = node->value<double>();
    if (!v || *v < 0 || *v >= 1)
      throw InputError("[firmware_state] minimum_cruise_ratio must be at least 0 and below 1 (klippy/toolhead.py)",
                       r.where_of(*node));
    st.minimum_cruise_ratio = *v;
  }
  st.steps_per_mm_x =
      r.positive(fs, "firmware_state", "steps_per_mm_x", false, firmware::limits::kMarlinDefaultStepsPerMmXY);
  st.steps_per_mm_y =
      r.positive(fs, "firmware_state", "steps_per_mm_y", false, firmware::limits::kMarlinDefaultStepsPerMmXY);
  st.min_segment_time_s =
      r.positive(fs, "firmware_state", "min_segment_time_s", false, firmware::limits::kMarlinDefaultMinSegmentTime_s);
  st.max_accel_xy_mm_s2 =
      r.positive(fs, "firmware_state", "max_accel_xy_mm_s2", false, firmware::limits::kMarlinDefaultMaxAccelXY_mm_s2);
  st.retract_accel_mm_s2 = r.positive(fs, "firmware_state", "retract_accel_mm_s2", false,
                                      firmware::limits::kMarlinDefaultRetractAccel_mm_s2);
  st.max_accel_e_mm_s2 = r.positive(fs, "firmware_state", "max_accel_e_mm_s2", false, p.extruder.max_accel_mm_s2);
  st.jerk_xy_mm_s = r.positive(fs, "firmware_state", "jerk_xy_mm_s", false, 15.0);
}

}  // namespace

MachineProfile parse_machine_profile(const std::string& text, const std::string& path) {
  toml::table root;
  detail::check_dotted_key_depth(text, path);
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(std::string(e.description()),
                     source_location(path, e.source().begin.line, e.source().begin.column));
  }
  Reader r(root, path);
  MachineProfile p;
  p.source_path = path;

  const auto& m = r.section("machine", true);
  p.name = m["name"].value_or(std::string("unnamed machine"));
  p.id = m["id"].value_or(std::string());
  p.kinematics = m["kinematics"].value_or(std::string("cartesian"));
  p.firmware = m["firmware"].value_or(std::string());
  if (p.kinematics != "cartesian" && p.kinematics != "corexy" && p.kinematics != "delta")
    throw InputError(fmt::format("unknown kinematics '{}' (cartesian, corexy, delta)", p.kinematics), path);

  read_axes(r, p, path);

  const auto& e = r.section("extruder", true);
  p.extruder.filament_diameter_mm = r.positive(e, "extruder", "filament_diameter_mm", false, 1.75);
  p.extruder.nozzle_diameter_mm = r.positive(e, "extruder", "nozzle_diameter_mm", false, 0.4);
  p.extruder.max_flow_mm3_s = r.positive(e, "extruder", "max_flow_mm3_s", true, 0);
  p.extruder.max_velocity_mm_s = r.positive(e, "extruder", "max_velocity_mm_s", true, 0);
  p.extruder.max_accel_mm_s2 = r.positive(e, "extruder", "max_accel_mm_s2", true, 0);
  // Klipper's default (klippy/kinematics/extruder.py:168-169); protocols split longer feeds.
  p.extruder.max_extrude_only_distance_mm = r.positive(e, "extruder", "max_extrude_only_distance_mm", false,
                                                       firmware::limits::kKlipperMaxExtrudeOnlyDistance_mm);

  const auto& pr = r.section("print", false);
  p.print.max_accel_mm_s2 = r.positive(pr, "print", "max_accel_mm_s2", false, 3000);
  p.print.line_width_mm = r.positive(pr, "print", "line_width_mm", false, 0.45);
  p.print.layer_height_mm = r.positive(pr, "print", "layer_height_mm", false, 0.2);
  p.print.speed_mm_s = r.positive(pr, "print", "speed_mm_s", false, 60);

  const auto& bt = r.section("belts", false);
  p.belts.belt = r.text(bt, "belt", "");
  p.belts.mass_g_m = r.positive(bt, "belts", "mass_g_m", false, 0);
  p.belts.span_mm = r.positive(bt, "belts", "span_mm", false, 0);
  p.belts.span_uncertainty_mm = r.positive(bt, "belts", "span_uncertainty_mm", false, 0);
  p.belts.target_n = r.positive(bt, "belts", "target_n", false, 0);

  const auto& tt = r.section("temperature", true);
  p.temperature.hotend_max_c = r.positive(tt, "temperature", "hotend_max_c", true, 0);
  p.temperature.bed_max_c = r.positive(tt, "temperature", "bed_max_c", false, 100);
  p.temperature.heaters_off_on_abort = r.flag(tt, "heaters_off_on_abort", true);

  read_sensors(r, p);

  read_network(r, p, path);

  read_firmware_state(r, p);
  check_physical_ranges(p, path);
  return p;
}

MachineProfile load_machine_profile(const std::string& path, std::string* bytes) {
  if (is_firmware_configuration(path)) return import_machine_profile(path, {}, bytes);  // profile_import.hpp
  std::string text = read_file_bytes(path);
  MachineProfile p = parse_machine_profile(text, path);
  if (bytes != nullptr) *bytes = std::move(text);
  return p;
}

}  // namespace tunekit::machine
