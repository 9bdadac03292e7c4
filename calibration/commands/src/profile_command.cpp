// tunekit profile: a machine profile from a firmware configuration (see profile_command.hpp).
#include "tunekit/calibration/commands/profile_command.hpp"

#include <fmt/format.h>

#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::calibration {
namespace {

nlohmann::json axes_json(const machine::MachineProfile& p) {
  nlohmann::json axes = nlohmann::json::object();
  for (const auto& [name, a] : p.axes)
    axes[name] = {{"min_mm", a.min_mm},
                  {"max_mm", a.max_mm},
                  {"max_velocity_mm_s", a.max_velocity_mm_s},
                  {"max_accel_mm_s2", a.max_accel_mm_s2}};
  return axes;
}

nlohmann::json profile_json(const machine::MachineProfile& p) {
  const auto& e = p.extruder;
  const auto& s = p.sensors;
  return {
      {"name", p.name},
      {"kinematics", p.kinematics},
      {"firmware", p.firmware},
      {"axes", axes_json(p)},
      {"extruder",
       {{"filament_diameter_mm", e.filament_diameter_mm},
        {"nozzle_diameter_mm", e.nozzle_diameter_mm},
        {"max_flow_mm3_s", e.max_flow_mm3_s},
        {"max_velocity_mm_s", e.max_velocity_mm_s},
        {"max_accel_mm_s2", e.max_accel_mm_s2},
        {"max_extrude_only_distance_mm", e.max_extrude_only_distance_mm}}},
      {"print",
       {{"max_accel_mm_s2", p.print.max_accel_mm_s2},
        {"line_width_mm", p.print.line_width_mm},
        {"layer_height_mm", p.print.layer_height_mm},
        {"speed_mm_s", p.print.speed_mm_s}}},
      {"temperature", {{"hotend_max_c", p.temperature.hotend_max_c}, {"bed_max_c", p.temperature.bed_max_c}}},
      {"sensors",
       {{"accelerometer", s.accelerometer},
        {"accelerometer_chip", s.accelerometer ? s.accelerometer_chip : ""},
        {"accelerometer_name", s.accelerometer ? s.accelerometer_name : ""},
        {"accelerometer_rate_hz", s.accelerometer_rate_hz},
        {"load_cell", s.load_cell},
        {"camera", s.camera},
        {"filament_encoder", s.filament_encoder}}},
      {"firmware_state",
       {{"shaper", p.state.shaper},
        {"minimum_cruise_ratio", p.state.minimum_cruise_ratio},
        {"accel_in_force_mm_s2", p.state.accel_in_force_mm_s2},
        {"steps_per_mm_x", p.state.steps_per_mm_x},
        {"steps_per_mm_y", p.state.steps_per_mm_y}}},
  };
}

}  // namespace

ProfileOutcome compute_profile(const ProfileOptions& options) {
  if (options.file.empty()) throw InputError("give the firmware configuration to import");
  if (!options.travel_mm.empty() && options.travel_mm.size() != 3)
    throw InputError("--travel takes three values: X,Y,Z (mm)");
  ProfileOutcome o;
  o.options = options;
  machine::ProfileImportOptions io;
  io.sensors = options.sensors;
  io.travel_mm = options.travel_mm;
  io.hotend_max_c = options.hotend_max_c;
  io.bed_max_c = options.bed_max_c;
  std::string bytes;  // as the import read them: the digest is of the bytes imported
  o.profile = machine::import_machine_profile(options.file, io, &bytes);
  o.input = input_digest(options.file, bytes);
  o.format = machine::to_string(machine::detect_config_format(bytes, options.file));
  if (o.profile.firmware.empty() || o.format == "toml") o.format = "toml";
  o.toml = machine::machine_profile_toml(o.profile);
  if (!options.output_toml.empty()) {
    check_output_not_input(options.output_toml, "-o", {options.file});
    write_output_text(options.output_toml, o.toml);
  }
  return o;
}

Envelope to_envelope(const ProfileOutcome& o) {
  Envelope env("profile");
  env.set_options({{"output", o.options.output_toml},
                   {"sensors", o.options.sensors},
                   {"travel_mm", o.options.travel_mm},
                   {"hotend_max_c", o.options.hotend_max_c},
                   {"bed_max_c", o.options.bed_max_c}});
  add_input(env, o.input);
  auto& r = env.results();
  r = profile_json(o.profile);
  r["format"] = o.format;
  r["sources"] = o.profile.sources;
  return env;
}

void print_text(const ProfileOutcome& o, std::ostream& os) {
  if (o.options.output_toml.empty()) {
    os << o.toml;
    return;
  }
  os << fmt::format("{}: {} configuration, {} kinematics: profile written to {}\n", o.options.file, o.format,
                    o.profile.kinematics, o.options.output_toml);
}

}  // namespace tunekit::calibration
