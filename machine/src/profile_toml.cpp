// A machine profile written as TOML that load_machine_profile() reads back, every value with its
// source as a comment.
#include <sstream>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {
namespace {

/// A comment's text: one line, no control characters (TOML forbids them in comments).
std::string comment_text(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    out.push_back(u < 0x20 || u == 0x7f ? ' ' : c);
  }
  return out;
}

std::string toml_quoted(const std::string& s) {
  std::ostringstream os;
  os << toml::value<std::string>(s);
  return os.str();
}

class ProfileTomlWriter {
 public:
  explicit ProfileTomlWriter(const MachineProfile& p) : p_(p) {}
  void table(const std::string& name) { out_ += fmt::format("\n[{}]\n", name); }
  void line(const std::string& key, const std::string& full_key, const std::string& value) {
    const auto it = p_.sources.find(full_key);
    const std::string src = it != p_.sources.end() ? it->second
                            : p_.sources.empty()   ? "read from " + p_.source_path + " (or the profile's default)"
                                                   : "not in the configuration: tunekit's default";
    out_ += fmt::format("{} = {}  # {}\n", key, value, comment_text(src));
  }
  void number(const std::string& table, const std::string& key, double v) {
    line(key, table + "." + key, fmt::format("{}", v));
  }
  void flag(const std::string& table, const std::string& key, bool v) {
    line(key, table + "." + key, v ? "true" : "false");
  }
  void text(const std::string& table, const std::string& key, const std::string& v) {
    line(key, table + "." + key, toml_quoted(v));
  }
  bool sourced(const std::string& full_key) const { return p_.sources.count(full_key) != 0; }
  std::string& out() { return out_; }

 private:
  const MachineProfile& p_;
  std::string out_;
};

void write_axes(ProfileTomlWriter& w, const MachineProfile& p) {
  for (const auto& [name, a] : p.axes) {
    const std::string t = "axes." + name;
    w.table(t);
    w.number(t, "min_mm", a.min_mm);
    w.number(t, "max_mm", a.max_mm);
    w.number(t, "max_velocity_mm_s", a.max_velocity_mm_s);
    w.number(t, "max_accel_mm_s2", a.max_accel_mm_s2);
  }
}

void write_extruder_print_temperature(ProfileTomlWriter& w, const MachineProfile& p) {
  w.table("extruder");
  const auto& e = p.extruder;
  w.number("extruder", "filament_diameter_mm", e.filament_diameter_mm);
  w.number("extruder", "nozzle_diameter_mm", e.nozzle_diameter_mm);
  w.number("extruder", "max_flow_mm3_s", e.max_flow_mm3_s);
  w.number("extruder", "max_velocity_mm_s", e.max_velocity_mm_s);
  w.number("extruder", "max_accel_mm_s2", e.max_accel_mm_s2);
  w.number("extruder", "max_extrude_only_distance_mm", e.max_extrude_only_distance_mm);
  w.table("print");
  w.number("print", "max_accel_mm_s2", p.print.max_accel_mm_s2);
  w.number("print", "line_width_mm", p.print.line_width_mm);
  w.number("print", "layer_height_mm", p.print.layer_height_mm);
  w.number("print", "speed_mm_s", p.print.speed_mm_s);
  w.table("temperature");
  w.number("temperature", "hotend_max_c", p.temperature.hotend_max_c);
  w.number("temperature", "bed_max_c", p.temperature.bed_max_c);
  w.flag("temperature", "heaters_off_on_abort", p.temperature.heaters_off_on_abort);
}

void write_sensors(ProfileTomlWriter& w, const MachineProfile& p) {
  const auto& s = p.sensors;
  w.table("sensors");
  if (s.accelerometer && is_klipper_accelerometer_chip(s.accelerometer_chip) && p.firmware == "klipper") {
    w.text("sensors", "accelerometer", s.accelerometer_chip);
    // A declared accelerometer without a section of its own keeps the chip's name (the default).
    if (!s.accelerometer_name.empty())
      w.line("accelerometer_name", "sensors.accelerometer", toml_quoted(s.accelerometer_name));
  } else {
    w.flag("sensors", "accelerometer", s.accelerometer);
  }
  w.number("sensors", "accelerometer_rate_hz", s.accelerometer_rate_hz);
  w.flag("sensors", "load_cell", s.load_cell);
  if (s.load_cell) w.line("load_cell_name", "sensors.load_cell", toml_quoted(s.load_cell_name));
  w.flag("sensors", "filament_encoder", s.filament_encoder);
  w.flag("sensors", "camera", s.camera);
}

/// [firmware_state]: only what the configuration set (the loader's defaults stand for the rest).
void write_state(ProfileTomlWriter& w, const MachineProfile& p) {
  const auto& st = p.state;
  w.table("firmware_state");
  for (const auto& [axis, v] : st.shaper) w.text("firmware_state", "shaper_" + axis, v);
  const std::pair<const char*, double> numbers[] = {
      {"minimum_cruise_ratio", st.minimum_cruise_ratio},
      {"steps_per_mm_x", st.steps_per_mm_x},
      {"steps_per_mm_y", st.steps_per_mm_y},
      {"min_segment_time_s", st.min_segment_time_s},
      {"max_accel_xy_mm_s2", st.max_accel_xy_mm_s2},
      {"retract_accel_mm_s2", st.retract_accel_mm_s2},
      {"max_accel_e_mm_s2", st.max_accel_e_mm_s2},
      {"jerk_xy_mm_s", st.jerk_xy_mm_s},
  };
  for (const auto& [key, v] : numbers)
    if (w.sourced(std::string("firmware_state.") + key)) w.number("firmware_state", key, v);
}

}  // namespace

std::string machine_profile_toml(const MachineProfile& p) {
  ProfileTomlWriter w(p);
  w.out() += fmt::format(
      "# Machine profile imported by tunekit from {} ({}).\n"
      "# Every value names its source: the file and line it was read from, the firmware's default and its\n"
      "# formula, or tunekit's default and its reason. Units are in the key names.\n",
      comment_text(p.source_path), p.firmware.empty() ? "TOML" : p.firmware);
  if (p.firmware == "klipper")
    w.out() +=
        "# Klipper's defaults and formulas: Kevin O'Connor et al., Klipper 3D printer firmware, klippy/, 2016-2026.\n";
  else if (p.firmware == "marlin")
    w.out() +=
        "# Marlin's defaults and rules: MarlinFirmware, Marlin 3D printer firmware 2.1, Marlin/src/, 2011-2026.\n";
  else if (p.firmware == "rrf")
    w.out() += "# RepRapFirmware's defaults: Duet3D, RepRapFirmware 3.5, src/, 2013-2026.\n";
  w.table("machine");
  w.text("machine", "name", p.name);
  if (!p.id.empty()) w.text("machine", "id", p.id);
  w.text("machine", "kinematics", p.kinematics);
  if (!p.firmware.empty()) w.text("machine", "firmware", p.firmware);
  write_axes(w, p);
  write_extruder_print_temperature(w, p);
  write_sensors(w, p);
  write_state(w, p);
  if (!p.http_address.empty()) {
    w.table("network");
    w.text("network", "http", p.http_address);
  }
  return w.out();
}

}  // namespace tunekit::machine
