// What the firmware-configuration importers share: sites, ranges, sourced values, tunekit's
// defaults for what no firmware configuration holds, the final check.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "profile_import_detail.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"

namespace tunekit::machine::detail {
namespace {

/// tunekit's hot-end flow limit when the configuration does not describe the hot end, mm^3/s: a
/// conservative figure for a stock hot end with a standard melt zone; the flow sweep runs to 90 %
/// of it. Set max_flow_mm3_s to the hot end's measured or published figure to test higher flows.
constexpr double kDefaultMaxFlow_mm3_s = 8.0;
/// The print's line width as a multiple of the nozzle diameter (0.45 mm for a 0.4 mm nozzle,
/// the TOML profile's default) and the layer height as a fraction of it (0.2 mm for 0.4 mm).
constexpr double kLineWidthPerNozzle = 1.125;
constexpr double kLayerHeightPerNozzle = 0.5;
/// The print speed when nothing says otherwise, mm/s (the TOML profile's default).
constexpr double kDefaultPrintSpeed_mm_s = 60.0;

}  // namespace

std::string Site::where() const { return line > 0 ? source_location(file, line) : file; }

std::string Site::cite() const {
  if (line == 0) return file;
  return text.empty() ? source_location(file, line) : fmt::format("{}:{} {}", file, line, text);
}

double checked(double v, const Range& range, const Site& site, const std::string& name) {
  const bool below = range.lo_open ? !(v > range.lo) : !(v >= range.lo);
  if (!std::isfinite(v) || below || !(v <= range.hi))
    throw InputError(fmt::format("{} = {} is not a plausible {} (it must be {} {:g} and at most {:g}{}{})", name,
                                 number_text(v), range.what, range.lo_open ? "above" : "at least", range.lo, range.hi,
                                 *range.unit ? " " : "", range.unit),
                     site.where());
  return v;
}

double parse_number(const std::string& text, const Range& range, const Site& site, const std::string& name) {
  const auto v = core::parse_decimal(text);
  if (!v) throw InputError(fmt::format("{} = '{}' is not a number", name, shown(text)), site.where());
  return checked(*v, range, site, name);
}

void set_value(MachineProfile& p, const std::string& key, double& field, double v, std::string source) {
  field = v;
  p.sources[key] = std::move(source);
}

void set_axis(MachineProfile& p, const std::string& name, const Sourced& lo, const Sourced& hi, const Sourced& v,
              const Sourced& a) {
  auto& ax = p.axes[name];
  const std::string k = "axes." + name + ".";
  set_value(p, k + "min_mm", ax.min_mm, lo.value, lo.source);
  set_value(p, k + "max_mm", ax.max_mm, hi.value, hi.source);
  set_value(p, k + "max_velocity_mm_s", ax.max_velocity_mm_s, v.value, v.source);
  set_value(p, k + "max_accel_mm_s2", ax.max_accel_mm_s2, a.value, a.source);
}

std::string shown(const std::string& text) { return text.size() > 60 ? text.substr(0, 60) + "..." : text; }

std::string number_text(double v) { return fmt::format("{}", v); }

void apply_common_defaults(MachineProfile& p) {
  auto& e = p.extruder;
  if (!p.sources.count("extruder.max_flow_mm3_s")) {
    const double feed_flow = e.max_velocity_mm_s * p.filament_area_mm2();
    const double flow = std::min(kDefaultMaxFlow_mm3_s, feed_flow);
    set_value(p, "extruder.max_flow_mm3_s", e.max_flow_mm3_s, flow,
              fmt::format("tunekit default: the firmware configuration does not describe the hot end's melting "
                          "limit; the smaller of a conservative {:g} mm^3/s for a stock hot end and the feed limit "
                          "x filament area ({:.4g} mm/s x {:.4g} mm^2 = {:.4g} mm^3/s); set it to the hot end's "
                          "measured or published figure",
                          kDefaultMaxFlow_mm3_s, e.max_velocity_mm_s, p.filament_area_mm2(), feed_flow));
  }
  const double d = e.nozzle_diameter_mm;
  if (!p.sources.count("print.line_width_mm"))
    set_value(p, "print.line_width_mm", p.print.line_width_mm, kLineWidthPerNozzle * d,
              fmt::format("tunekit default: {:g} x the nozzle diameter {:g} mm", kLineWidthPerNozzle, d));
  if (!p.sources.count("print.layer_height_mm"))
    set_value(p, "print.layer_height_mm", p.print.layer_height_mm, kLayerHeightPerNozzle * d,
              fmt::format("tunekit default: {:g} x the nozzle diameter {:g} mm", kLayerHeightPerNozzle, d));
  if (!p.sources.count("print.speed_mm_s")) {
    const auto it = p.axes.find("x");
    const double vmax = it != p.axes.end() ? it->second.max_velocity_mm_s : kDefaultPrintSpeed_mm_s;
    set_value(p, "print.speed_mm_s", p.print.speed_mm_s, std::min(kDefaultPrintSpeed_mm_s, vmax),
              fmt::format("tunekit default: {:g} mm/s, at most the X axis' speed limit", kDefaultPrintSpeed_mm_s));
  }
  for (const char* s : {"accelerometer", "load_cell", "camera", "filament_encoder"})
    p.sources.try_emplace(
        std::string("sensors.") + s,
        fmt::format("the configuration declares no {0}; declare one with tunekit profile --sensor {0}", s));
  p.sources.try_emplace("sensors.accelerometer_rate_hz",
                        "no accelerometer in the configuration: the profile's default sample rate");
  p.temperature.heaters_off_on_abort = true;
  p.sources["temperature.heaters_off_on_abort"] = "tunekit default: heaters off when a test is aborted";
}

void apply_sensor_options(MachineProfile& p, const ProfileImportOptions& options) {
  for (const auto& raw : options.sensors) {
    const std::string s = core::lower(raw);
    const std::string why = "declared on the command line (--sensor " + s + ")";
    if (s == "accelerometer") p.sensors.accelerometer = true;
    else if (s == "load_cell" || s == "load-cell") p.sensors.load_cell = true;
    else if (s == "camera") p.sensors.camera = true;
    else if (s == "filament_encoder" || s == "filament-encoder") p.sensors.filament_encoder = true;
    else
      throw InputError(
          fmt::format("--sensor {}: not a sensor tunekit reads (accelerometer, load_cell, camera, "
                      "filament_encoder)",
                      raw));
    p.sources["sensors." + (s == "load-cell" ? std::string("load_cell") : s)] = why;
  }
}

void check_imported(const MachineProfile& p) {
  const auto bad = [&](const std::string& key, double v) {
    const auto it = p.sources.find(key);
    throw InputError(fmt::format("{} = {} is not a usable limit (from {})", key, number_text(v),
                                 it == p.sources.end() ? "no source" : it->second),
                     p.source_path);
  };
  const auto positive = [&](const std::string& key, double v) {
    if (!(std::isfinite(v) && v > 0)) bad(key, v);
  };
  for (const char* name : {"x", "y", "z"}) {
    const auto it = p.axes.find(name);
    if (it == p.axes.end()) throw InputError(fmt::format("no travel for the {} axis", name), p.source_path);
    const auto& a = it->second;
    const std::string k = std::string("axes.") + name;
    if (!(std::isfinite(a.min_mm) && std::isfinite(a.max_mm) && a.max_mm > a.min_mm)) bad(k + ".max_mm", a.max_mm);
    positive(k + ".max_velocity_mm_s", a.max_velocity_mm_s);
    positive(k + ".max_accel_mm_s2", a.max_accel_mm_s2);
  }
  positive("extruder.filament_diameter_mm", p.extruder.filament_diameter_mm);
  positive("extruder.nozzle_diameter_mm", p.extruder.nozzle_diameter_mm);
  positive("extruder.max_flow_mm3_s", p.extruder.max_flow_mm3_s);
  positive("extruder.max_velocity_mm_s", p.extruder.max_velocity_mm_s);
  positive("extruder.max_accel_mm_s2", p.extruder.max_accel_mm_s2);
  positive("extruder.max_extrude_only_distance_mm", p.extruder.max_extrude_only_distance_mm);
  positive("print.max_accel_mm_s2", p.print.max_accel_mm_s2);
  positive("temperature.hotend_max_c", p.temperature.hotend_max_c);
  positive("temperature.bed_max_c", p.temperature.bed_max_c);
}

}  // namespace tunekit::machine::detail
