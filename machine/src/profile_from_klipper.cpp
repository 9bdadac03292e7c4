// A machine profile from a Klipper printer.cfg: the limits Klipper computes from the file,
// defaults included (Kevin O'Connor et al., Klipper 3D printer firmware, klippy/toolhead.py,
// klippy/stepper.py, klippy/kinematics/{extruder,cartesian,corexy,delta}.py, klippy/extras/
// {heaters,input_shaper,resonance_tester,adxl345,lis2dw,mpu9250,icm20948,bmi160}.py, 2016-2026).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>

#include <fmt/format.h>

#include "klipper_config_reader.hpp"
#include "profile_import_detail.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {
namespace {

using detail::KlipperConfig;
using detail::KlipperSection;
using detail::Range;
using detail::Sourced;

class KlipperView {
 public:
  explicit KlipperView(const KlipperConfig& c) : c_(c) {}

  const KlipperSection& section(const std::string& name) const {
    const auto* s = c_.find(name);
    if (s == nullptr) throw InputError(fmt::format("no [{}] section", name), c_.main_file);
    return *s;
  }
  bool has(const std::string& name) const { return c_.find(name) != nullptr; }
  const KlipperConfig& config() const { return c_; }

  /// The option's number, or `fallback` when the option is absent (required when nullopt).
  Sourced number(const std::string& sec, const std::string& key, const Range& range,
                 const std::optional<Sourced>& fallback = std::nullopt) const {
    const auto& s = section(sec);
    const auto* o = s.find(key);
    if (o == nullptr) {
      if (fallback) return *fallback;
      throw InputError(fmt::format("[{}] needs '{}'", sec, key), s.site.where());
    }
    return {detail::parse_number(o->value, range, o->site, fmt::format("[{}] {}", sec, key)), cite(sec, *o)};
  }
  std::optional<std::string> text(const std::string& sec, const std::string& key) const {
    const auto* s = c_.find(sec);
    const auto* o = s ? s->find(key) : nullptr;
    return o ? std::optional<std::string>(o->value) : std::nullopt;
  }
  static std::string cite(const std::string& sec, const detail::KlipperOption& o) {
    return fmt::format("{} [{}] {}", o.site.where(), sec, o.site.text);
  }

 private:
  const KlipperConfig& c_;
};

Sourced klipper_default(double v, const std::string& file, const std::string& formula) {
  return {v, fmt::format("Klipper default ({}): {}", file, formula)};
}

/// klippy/stepper.py parse_step_distance / parse_gear_ratio: full steps x microsteps x gearing
/// per rotation_distance.
Sourced klipper_steps_per_mm(const KlipperView& k, const std::string& sec) {
  const auto rd = k.number(sec, "rotation_distance", detail::kLength);
  const auto ms = k.number(sec, "microsteps", detail::kCount);
  const auto fs = k.number(sec, "full_steps_per_rotation", detail::kCount,
                           klipper_default(200, "klippy/stepper.py", "full_steps_per_rotation 200"));
  const auto& s = k.section(sec);
  if (std::fmod(fs.value, 4.0) != 0 || std::floor(ms.value) != ms.value)
    throw InputError(fmt::format("[{}] full_steps_per_rotation must be a multiple of 4 and microsteps a whole "
                                 "number (klippy/stepper.py)",
                                 sec),
                     s.site.where());
  double gearing = 1;
  std::string gear_text;
  if (const auto* g = s.find("gear_ratio"); g != nullptr && !g->value.empty()) {
    std::string list = g->value;
    std::replace(list.begin(), list.end(), '\n', ',');
    std::size_t start = 0;
    while (start <= list.size()) {
      const auto end = std::min(list.find(',', start), list.size());
      const std::string pair = list.substr(start, end - start);
      const auto colon = pair.find(':');
      if (colon == std::string::npos)
        throw InputError(fmt::format("[{}] gear_ratio '{}' is not a list of A:B pairs", sec, g->value),
                         g->site.where());
      const auto trim = [](std::string t) {
        t.erase(0, t.find_first_not_of(" \t"));
        t.erase(t.find_last_not_of(" \t") + 1);
        return t;
      };
      const double a = detail::parse_number(trim(pair.substr(0, colon)), detail::kCount, g->site, sec + " gear_ratio");
      const double b = detail::parse_number(trim(pair.substr(colon + 1)), detail::kCount, g->site, sec + " gear_ratio");
      gearing *= a / b;
      start = end + 1;
    }
    gear_text = fmt::format(" x gear_ratio {}", g->value);
  }
  const double steps = fs.value * ms.value * gearing / rd.value;
  return {detail::checked(steps, detail::kStepsPerMm, s.site, "[" + sec + "] steps per mm"),
          fmt::format("klippy/stepper.py: full_steps_per_rotation {} x microsteps {}{} / rotation_distance {} "
                      "= {:.6g} steps/mm ({}; {})",
                      fs.value, ms.value, gear_text, rd.value, steps, rd.source, ms.source)};
}

struct KlipperToolhead {
  Sourced max_velocity, max_accel, max_z_velocity, max_z_accel;
};

KlipperToolhead read_klipper_printer(const KlipperView& k, MachineProfile& p) {
  KlipperToolhead t;
  t.max_velocity = k.number("printer", "max_velocity", detail::kVelocity);
  t.max_accel = k.number("printer", "max_accel", detail::kAccel);
  const std::string kin_file = "klippy/kinematics/" + p.kinematics + ".py";
  t.max_z_velocity = k.number("printer", "max_z_velocity", detail::kVelocity,
                              klipper_default(t.max_velocity.value, kin_file, "max_z_velocity = max_velocity"));
  t.max_z_accel = k.number("printer", "max_z_accel", detail::kAccel,
                           klipper_default(t.max_accel.value, kin_file, "max_z_accel = max_accel"));
  const auto mcr = k.number("printer", "minimum_cruise_ratio", detail::kFraction,
                            klipper_default(firmware::limits::kKlipperMinimumCruiseRatioDefault, "klippy/toolhead.py",
                                            "minimum_cruise_ratio 0.5"));
  if (!(mcr.value < 1))
    throw InputError("[printer] minimum_cruise_ratio must be below 1 (klippy/toolhead.py)",
                     k.section("printer").site.where());
  detail::set_value(p, "firmware_state.minimum_cruise_ratio", p.state.minimum_cruise_ratio, mcr.value, mcr.source);
  detail::set_value(p, "print.max_accel_mm_s2", p.print.max_accel_mm_s2, t.max_accel.value, t.max_accel.source);
  detail::set_value(p, "firmware_state.accel_in_force_mm_s2", p.state.accel_in_force_mm_s2, t.max_accel.value,
                    t.max_accel.source);
  return t;
}

/// cartesian and corexy: each axis' rail [stepper_<axis>] position_min (default 0) to position_max.
void read_klipper_rails(const KlipperView& k, MachineProfile& p, const KlipperToolhead& t) {
  for (const std::string axis : {"x", "y", "z"}) {
    const std::string sec = "stepper_" + axis;
    const auto lo =
        k.number(sec, "position_min", detail::kPosition, klipper_default(0, "klippy/stepper.py", "position_min 0"));
    const auto hi = k.number(sec, "position_max", detail::kPosition);
    if (!(hi.value > lo.value))
      throw InputError(fmt::format("[{}] position_max must be above position_min (klippy/stepper.py)", sec),
                       k.section(sec).site.where());
    const bool z = axis == "z";
    detail::set_axis(p, axis, lo, hi, z ? t.max_z_velocity : t.max_velocity, z ? t.max_z_accel : t.max_accel);
  }
  const auto sx = klipper_steps_per_mm(k, "stepper_x"), sy = klipper_steps_per_mm(k, "stepper_y");
  detail::set_value(p, "firmware_state.steps_per_mm_x", p.state.steps_per_mm_x, sx.value, sx.source);
  detail::set_value(p, "firmware_state.steps_per_mm_y", p.state.steps_per_mm_y, sy.value, sy.source);
}

struct KlipperDeltaTowers {
  double radius = 0, print_radius = 0, min_arm = 0, min_step = 0, max_z = 0, limit_z = 0;
  std::string radius_source, print_radius_source;
};

KlipperDeltaTowers read_klipper_towers(const KlipperView& k) {
  KlipperDeltaTowers d;
  const auto radius = k.number("printer", "delta_radius", detail::kLength);
  const auto print_radius =
      k.number("printer", "print_radius", detail::kLength,
               klipper_default(radius.value, "klippy/kinematics/delta.py", "print_radius = delta_radius"));
  d.radius = radius.value;
  d.print_radius = print_radius.value;
  d.radius_source = radius.source;
  d.print_radius_source = print_radius.source;
  const auto arm_a = k.number("stepper_a", "arm_length", detail::kLength);
  const auto end_a = k.number("stepper_a", "position_endstop", detail::kPosition);
  d.min_arm = d.min_step = d.max_z = d.limit_z = std::numeric_limits<double>::infinity();
  for (const std::string tower : {"stepper_a", "stepper_b", "stepper_c"}) {
    const double arm = k.number(tower, "arm_length", detail::kLength, arm_a).value;
    const double endstop = k.number(tower, "position_endstop", detail::kPosition, end_a).value;
    if (!(arm > d.radius))
      throw InputError(fmt::format("[{}] arm_length must be above delta_radius (klippy/kinematics/delta.py)", tower),
                       k.section(tower).site.where());
    const double step = 1.0 / klipper_steps_per_mm(k, tower).value;
    d.min_arm = std::min(d.min_arm, arm);
    d.min_step = std::min(d.min_step, step);
    d.max_z = std::min(d.max_z, endstop);
    d.limit_z = std::min(d.limit_z, endstop + std::sqrt(arm * arm - d.radius * d.radius) - arm);
  }
  return d;
}

/// delta: klippy/kinematics/delta.py's build radius max_xy (print_radius, arm length - radius, the
/// radius where a tower would move 12 times faster than the head) and heights. tunekit's profile
/// is a box, so X and Y span the square inside that circle, +-max_xy/sqrt(2), and Z ends where
/// Klipper starts tapering the radius (limit_z) if that is below the homed height.
void read_klipper_delta(const KlipperView& k, MachineProfile& p, const KlipperToolhead& t) {
  const KlipperDeltaTowers d = read_klipper_towers(k);
  const double half_step = 0.5 * d.min_step, ratio = 12.0;
  const double ratio_xy =
      ratio * std::sqrt(d.min_arm * d.min_arm / (ratio * ratio + 1) - half_step * half_step) + half_step - d.radius;
  const double max_xy = std::min({d.print_radius, d.min_arm - d.radius, ratio_xy});
  const double half = max_xy / std::numbers::sqrt2;
  const std::string why = fmt::format(
      "klippy/kinematics/delta.py: build radius max_xy = min(print_radius {:g}, arm_length {:g} - delta_radius "
      "{:g}, {:.4g} where a tower moves 12x the head) = {:.6g} mm; tunekit's travel is a box: the square inside "
      "that circle, max_xy / sqrt(2) = {:.6g} mm ({})",
      d.print_radius, d.min_arm, d.radius, ratio_xy, max_xy, half, d.print_radius_source);
  const Sourced lo{-half, why}, hi{half, why};
  detail::set_axis(p, "x", lo, hi, t.max_velocity, t.max_accel);
  detail::set_axis(p, "y", lo, hi, t.max_velocity, t.max_accel);
  const auto zmin = k.number("printer", "minimum_z_position", detail::kPosition,
                             klipper_default(0, "klippy/kinematics/delta.py", "minimum_z_position 0"));
  const double zmax = std::min(d.max_z, d.limit_z);
  const Sourced ztop{zmax, fmt::format("klippy/kinematics/delta.py: the lowest tower position_endstop {:.6g} mm, "
                                       "or where the build radius starts to taper (limit_z {:.6g} mm) if lower",
                                       d.max_z, d.limit_z)};
  if (!(zmax > zmin.value))
    throw InputError("the delta's homed height is not above minimum_z_position", k.section("printer").site.where());
  detail::set_axis(p, "z", zmin, ztop, t.max_z_velocity, t.max_z_accel);
  const auto sa = klipper_steps_per_mm(k, "stepper_a");
  detail::set_value(p, "firmware_state.steps_per_mm_x", p.state.steps_per_mm_x, sa.value, sa.source);
  detail::set_value(p, "firmware_state.steps_per_mm_y", p.state.steps_per_mm_y, sa.value, sa.source);
}

/// [extruder]: klippy/kinematics/extruder.py PrinterExtruder.__init__ and heaters.py max_temp.
void read_klipper_extruder(const KlipperView& k, MachineProfile& p, const KlipperToolhead& t) {
  auto& e = p.extruder;
  const auto d = k.number("extruder", "nozzle_diameter", detail::kDiameter);
  const auto fd = k.number("extruder", "filament_diameter", detail::kDiameter);
  if (fd.value < d.value)
    throw InputError("[extruder] filament_diameter must be at least nozzle_diameter (extruder.py)",
                     k.section("extruder").site.where());
  detail::set_value(p, "extruder.nozzle_diameter_mm", e.nozzle_diameter_mm, d.value, d.source);
  detail::set_value(p, "extruder.filament_diameter_mm", e.filament_diameter_mm, fd.value, fd.source);
  const double area = std::numbers::pi * (0.5 * fd.value) * (0.5 * fd.value);
  const double ratio = 4.0 * d.value * d.value / area;  // def_max_cross_section / filament_area
  const std::string f = "klippy/kinematics/extruder.py";
  const auto ev = k.number(
      "extruder", "max_extrude_only_velocity", detail::kVelocity,
      klipper_default(t.max_velocity.value * ratio, f,
                      fmt::format("max_velocity * 4 d^2 / (pi (D/2)^2) = {} * 4 * {}^2 / (pi ({}/2)^2) = {:.1f}",
                                  t.max_velocity.value, d.value, fd.value, t.max_velocity.value * ratio)));
  const auto ea =
      k.number("extruder", "max_extrude_only_accel", detail::kAccel,
               klipper_default(t.max_accel.value * ratio, f,
                               fmt::format("max_accel * 4 d^2 / (pi (D/2)^2) = {} * 4 * {}^2 / (pi ({}/2)^2) = {:.1f}",
                                           t.max_accel.value, d.value, fd.value, t.max_accel.value * ratio)));
  const auto dist =
      k.number("extruder", "max_extrude_only_distance", detail::kLength,
               klipper_default(firmware::limits::kKlipperMaxExtrudeOnlyDistance_mm, f, "max_extrude_only_distance 50"));
  detail::set_value(p, "extruder.max_velocity_mm_s", e.max_velocity_mm_s, ev.value, ev.source);
  detail::set_value(p, "extruder.max_accel_mm_s2", e.max_accel_mm_s2, ea.value, ea.source);
  detail::set_value(p, "extruder.max_extrude_only_distance_mm", e.max_extrude_only_distance_mm, dist.value,
                    dist.source);
  const auto tmax = k.number("extruder", "max_temp", detail::kTemperature);
  detail::set_value(p, "temperature.hotend_max_c", p.temperature.hotend_max_c, tmax.value, tmax.source);
}

void read_klipper_bed(const KlipperView& k, MachineProfile& p) {
  if (k.has("heater_bed")) {
    const auto b = k.number("heater_bed", "max_temp", detail::kTemperature);
    detail::set_value(p, "temperature.bed_max_c", p.temperature.bed_max_c, b.value, b.source);
    return;
  }
  detail::set_value(p, "temperature.bed_max_c", p.temperature.bed_max_c, 1.0,
                    "no [heater_bed]: the machine has no heated bed; 1 degC lets no bed heating pass tunekit's "
                    "safety check (a profile needs a positive number)");
}

/// klippy/extras/input_shaper.py: shaper_freq_<axis> (0: off), shaper_type_<axis> falling back to
/// shaper_type (default mzv), damping_ratio_<axis> (default 0.1, shaper_defs.py).
void read_klipper_input_shaper(const KlipperView& k, MachineProfile& p) {
  if (!k.has("input_shaper")) return;
  for (const std::string axis : {"x", "y"}) {
    const auto freq = k.number("input_shaper", "shaper_freq_" + axis, detail::kFrequency,
                               klipper_default(0, "klippy/extras/input_shaper.py", "0 (off)"));
    if (!(freq.value > 0)) continue;
    const std::string type = core::lower(
        k.text("input_shaper", "shaper_type_" + axis).value_or(k.text("input_shaper", "shaper_type").value_or("mzv")));
    const auto zeta = k.number("input_shaper", "damping_ratio_" + axis, detail::kFraction,
                               klipper_default(0.1, "klippy/extras/shaper_defs.py", "DEFAULT_DAMPING_RATIO 0.1"));
    p.state.shaper[axis] = fmt::format("{}:{}:{}", type, freq.value, zeta.value);
    p.sources["firmware_state.shaper_" + axis] = fmt::format("{}; type {}; damping {}", freq.source, type, zeta.source);
  }
}

/// The accelerometer's default sample rate, Hz (each chip's module in klippy/extras).
double klipper_accelerometer_rate(const std::string& chip) {
  if (chip == "adxl345") return 3200;
  if (chip == "mpu9250" || chip == "mpu6050") return 4000;
  if (chip == "icm20948") return 4500;
  if (chip == "lis3dh") return 1344;
  return 1600;  // lis2dw, bmi160
}

/// Accelerometer sections ([adxl345], [lis2dw toolhead], ...): the one [resonance_tester]
/// accel_chip (or accel_chip_x) names, else the first; [load_cell] / [load_cell NAME].
void read_klipper_sensors(const KlipperView& k, MachineProfile& p) {
  std::string chosen;
  if (const auto named = k.text("resonance_tester", "accel_chip"); named && k.has(*named)) chosen = *named;
  else if (const auto nx = k.text("resonance_tester", "accel_chip_x"); nx && k.has(*nx)) chosen = *nx;
  for (const auto& [name, sec] : k.config().sections) {
    const std::string chip = name.substr(0, name.find(' '));
    if (chosen.empty() && is_klipper_accelerometer_chip(chip)) chosen = name;
    if (chip == "load_cell" && !p.sensors.load_cell) {
      p.sensors.load_cell = true;
      p.sensors.load_cell_name = name;
      p.sources["sensors.load_cell"] = fmt::format("{} [{}]", sec.site.where(), name);
    }
  }
  if (chosen.empty()) return;
  const auto& sec = k.section(chosen);
  p.sensors.accelerometer = true;
  p.sensors.accelerometer_chip = chosen.substr(0, chosen.find(' '));
  p.sensors.accelerometer_name = chosen;
  p.sources["sensors.accelerometer"] = fmt::format("{} [{}]", sec.site.where(), chosen);
  const auto rate = k.number(chosen, "rate", detail::kFrequency,
                             klipper_default(klipper_accelerometer_rate(p.sensors.accelerometer_chip),
                                             "klippy/extras/" + p.sensors.accelerometer_chip + ".py", "its rate"));
  detail::set_value(p, "sensors.accelerometer_rate_hz", p.sensors.accelerometer_rate_hz, rate.value, rate.source);
}

void read_klipper_kinematics(const KlipperView& k, MachineProfile& p) {
  const auto& printer = k.section("printer");
  const auto* kin = printer.find("kinematics");
  if (kin == nullptr) throw InputError("[printer] needs 'kinematics'", printer.site.where());
  const std::string name = core::lower(kin->value);
  if (name != "cartesian" && name != "corexy" && name != "delta")
    throw InputError(
        fmt::format("[printer] kinematics '{}' is not one tunekit supports (cartesian, corexy, delta)", kin->value),
        kin->site.where());
  p.kinematics = name;
  p.sources["machine.kinematics"] = KlipperView::cite("printer", *kin);
}

}  // namespace

MachineProfile profile_from_klipper(const std::string& path, const ProfileImportOptions& options) {
  const KlipperConfig cfg = detail::read_klipper_config(path);
  const KlipperView k(cfg);
  MachineProfile p;
  p.source_path = path;
  p.firmware = "klipper";
  p.sources["machine.firmware"] = fmt::format("{}: a Klipper printer.cfg", path);
  p.name = std::filesystem::path(path).stem().string();
  p.sources["machine.name"] = "the configuration file's name";
  read_klipper_kinematics(k, p);
  const KlipperToolhead t = read_klipper_printer(k, p);
  if (p.kinematics == "delta") read_klipper_delta(k, p, t);
  else read_klipper_rails(k, p, t);
  read_klipper_extruder(k, p, t);
  read_klipper_bed(k, p);
  read_klipper_input_shaper(k, p);
  read_klipper_sensors(k, p);
  detail::apply_sensor_options(p, options);
  detail::apply_common_defaults(p);
  detail::check_imported(p);
  return p;
}

}  // namespace tunekit::machine
