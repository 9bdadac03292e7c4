// A machine profile from a RepRapFirmware config.g, its commands taken in order as the firmware
// runs them at start-up (Duet3D, RepRapFirmware 3.5 G-code dictionary and source
// src/GCodes/GCodes2.cpp, src/Config/Configuration.h, 2013-2026):
//  M92 steps/mm (S: the microstepping they are given for), M350 microstepping (changing it
//  rescales steps/mm: GCodes::ChangeMicrostepping), M203 mm/min, M201 mm/s^2, M204 P/T mm/s^2,
//  M566 mm/min, M208 S1 minima / S0 maxima (or X0:220), M669 K kinematics (M667 S1 CoreXY),
//  M665 delta geometry (B printable radius, H homed height), M143 H heater limit, M140 H bed
//  heater, M563 P0 H tool 0's heater, M593 P"type" F S input shaper, M955 accelerometer.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "profile_import_detail.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {
namespace {

using detail::Site;
using detail::Sourced;

/// RepRapFirmware's defaults (src/Config/Configuration.h): x16 microstepping; the heater limit
/// DefaultHotEndTemperatureLimit is 285 or 290 degC by version (the lower is taken),
/// DefaultBedTemperatureLimit 125 degC; M204's default is higher than any M201 limit.
constexpr double kRrfDefaultMicrostepping = 16;
constexpr double kRrfDefaultHotendLimit_c = 285;
constexpr double kRrfDefaultBedLimit_c = 125;

struct RrfLine {
  std::string command;                ///< "M208"
  std::map<char, std::string> words;  ///< 'X' -> "0:220", 'P' -> "\"mzv\""
  Site site;
};

/// One line's command and words; nullopt for comments, blank lines and meta commands.
std::optional<RrfLine> rrf_parse(const std::string& raw, const Site& site) {
  std::string t;
  bool quoted = false;
  for (char c : raw) {
    if (c == '"') quoted = !quoted;
    if (c == ';' && !quoted) break;
    t.push_back(c);
  }
  std::istringstream in(t);
  RrfLine l{{}, {}, site};
  if (!(in >> l.command) || l.command.size() < 2 || !std::isdigit(static_cast<unsigned char>(l.command[1])))
    return std::nullopt;
  l.command[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(l.command[0])));
  for (std::string w; in >> w;) {
    if (!std::isalpha(static_cast<unsigned char>(w[0]))) continue;
    const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])));
    std::string v = w.substr(1);
    while (std::count(v.begin(), v.end(), '"') % 2 == 1 && in >> w) v += " " + w;
    l.words[letter] = v;
  }
  return l;
}

/// The state config.g leaves the machine in.
struct RrfState {
  std::map<char, Sourced> steps, microsteps, feed, accel, jerk, lo, hi;
  std::map<int, Sourced> heater_limit;
  int bed_heater = 0, tool_heater = 1;
  std::optional<Sourced> print_accel, kinematics, delta_radius, delta_height;
  std::string kinematics_name = "cartesian";
  std::optional<std::pair<std::string, std::string>> shaper;  ///< (value, source)
  std::optional<std::string> accelerometer;
};

class RrfReader {
 public:
  explicit RrfReader(const std::string& path) : path_(path) {}
  RrfState run();

 private:
  /// The first value of a word ("415:415" -> 415), checked.
  double value(const RrfLine& l, char w, const detail::Range& r) const {
    const std::string& v = l.words.at(w);
    return detail::parse_number(v.substr(0, v.find(':')), r, l.site, fmt::format("{} {}", l.command, w));
  }
  void per_axis(const RrfLine& l, std::map<char, Sourced>& into, const detail::Range& r, double scale,
                const std::string& note) {
    for (char a : {'X', 'Y', 'Z', 'E'})
      if (l.words.count(a)) into[a] = Sourced{value(l, a, r) * scale, l.site.cite() + note};
  }
  void steps(const RrfLine& l);
  void microstepping(const RrfLine& l);
  void limits(const RrfLine& l);
  void kinematics(const RrfLine& l);
  void heaters(const RrfLine& l);
  void shaper(const RrfLine& l);
  void dispatch(const RrfLine& l);
  std::string path_;
  RrfState s_;
};

void RrfReader::steps(const RrfLine& l) {
  for (char a : {'X', 'Y', 'Z', 'E'}) {
    if (!l.words.count(a)) continue;
    double v = value(l, a, detail::kStepsPerMm);
    const double ms = s_.microsteps.count(a) ? s_.microsteps[a].value : kRrfDefaultMicrostepping;
    std::string note;
    if (l.words.count('S')) {  // steps given for S microstepping: scaled to the microstepping in use
      const double given = value(l, 'S', detail::kCount);
      v *= ms / given;
      note = fmt::format(" (given for x{:g} microstepping, x{:g} in use)", given, ms);
    }
    s_.steps[a] = Sourced{v, l.site.cite() + note};
  }
}

void RrfReader::microstepping(const RrfLine& l) {
  for (char a : {'X', 'Y', 'Z', 'E'}) {
    if (!l.words.count(a)) continue;
    const double ms = value(l, a, detail::kCount);
    const double old = s_.microsteps.count(a) ? s_.microsteps[a].value : kRrfDefaultMicrostepping;
    if (s_.steps.count(a) && ms != old)
      s_.steps[a] = Sourced{s_.steps[a].value * ms / old,
                            fmt::format("{}; then {}: microstepping x{:g} -> x{:g} rescales steps/mm "
                                        "(src/GCodes/GCodes.cpp ChangeMicrostepping)",
                                        s_.steps[a].source, l.site.cite(), old, ms)};
    s_.microsteps[a] = Sourced{ms, l.site.cite()};
  }
}

/// M208: S1 minima, S0 (default) maxima, or min:max pairs.
void RrfReader::limits(const RrfLine& l) {
  const bool minima = l.words.count('S') && value(l, 'S', detail::Range{0, 1, false, "flag", ""}) == 1;
  for (char a : {'X', 'Y', 'Z'}) {
    if (!l.words.count(a)) continue;
    const std::string& v = l.words.at(a);
    const auto colon = v.find(':');
    const auto num = [&](const std::string& text) {
      return detail::parse_number(text, detail::kPosition, l.site, fmt::format("M208 {}", a));
    };
    if (colon != std::string::npos) {
      s_.lo[a] = Sourced{num(v.substr(0, colon)), l.site.cite()};
      s_.hi[a] = Sourced{num(v.substr(colon + 1)), l.site.cite()};
    } else {
      (minima ? s_.lo : s_.hi)[a] = Sourced{num(v), l.site.cite()};
    }
  }
}

void RrfReader::kinematics(const RrfLine& l) {
  if (l.command == "M667") {
    if (l.words.count('S') && value(l, 'S', detail::Range{0, 10, false, "mode", ""}) == 1)
      s_.kinematics_name = "corexy", s_.kinematics = Sourced{1, l.site.cite()};
    return;
  }
  if (l.command == "M665") {
    s_.kinematics_name = "delta";
    s_.kinematics = Sourced{3, l.site.cite()};
    if (l.words.count('B')) s_.delta_radius = Sourced{value(l, 'B', detail::kLength), l.site.cite()};
    if (l.words.count('H')) s_.delta_height = Sourced{value(l, 'H', detail::kLength), l.site.cite()};
    return;
  }
  if (!l.words.count('K')) return;  // M669 without K: other parameters of the kinematics in force
  const double k = value(l, 'K', detail::Range{0, 100, false, "kinematics number", ""});
  const char* name = k == 0 ? "cartesian" : k == 1 ? "corexy" : k == 3 ? "delta" : nullptr;
  if (name == nullptr)
    throw InputError(fmt::format("M669 K{:g}: kinematics not one tunekit supports (K0 cartesian, K1 CoreXY, K3 "
                                 "linear delta)",
                                 k),
                     l.site.where());
  s_.kinematics_name = name;
  s_.kinematics = Sourced{k, l.site.cite()};
}

void RrfReader::heaters(const RrfLine& l) {
  const detail::Range index{0, 1000, false, "heater number", ""};
  if (l.command == "M143") {
    const int h = l.words.count('H') ? static_cast<int>(value(l, 'H', index)) : 1;  // RRF: H defaults to 1
    if (l.words.count('S')) s_.heater_limit[h] = Sourced{value(l, 'S', detail::kTemperature), l.site.cite()};
  } else if (l.command == "M140" && l.words.count('H')) {
    s_.bed_heater = static_cast<int>(value(l, 'H', detail::Range{-1, 1000, false, "heater number", ""}));
  } else if (l.command == "M563" && l.words.count('H') && l.words.count('P') && value(l, 'P', index) == 0) {
    s_.tool_heater = static_cast<int>(value(l, 'H', index));
  }
}

/// M593 P"type" F<Hz> S<damping>: one shaper for the X and Y axes; P"none" or F0 turns it off.
void RrfReader::shaper(const RrfLine& l) {
  std::string type;
  if (l.words.count('P')) {
    type = core::lower(l.words.at('P'));
    type.erase(std::remove(type.begin(), type.end(), '"'), type.end());
  }
  if (type.empty() || type == "none" || !l.words.count('F') || !(value(l, 'F', detail::kFrequency) > 0)) {
    s_.shaper.reset();
    return;
  }
  const double zeta = l.words.count('S') ? value(l, 'S', detail::kFraction) : 0.1;
  s_.shaper = std::make_pair(fmt::format("{}:{}:{}", type, value(l, 'F', detail::kFrequency), zeta), l.site.cite());
}

void RrfReader::dispatch(const RrfLine& l) {
  const std::string& c = l.command;
  if (c == "M92") steps(l);
  else if (c == "M350") microstepping(l);
  else if (c == "M203")
    per_axis(l, s_.feed, detail::Range{0, 6e6, true, "speed", "mm/min"}, 1.0 / 60, " (mm/min / 60)");
  else if (c == "M201") per_axis(l, s_.accel, detail::kAccel, 1.0, "");
  else if (c == "M566")
    per_axis(l, s_.jerk, detail::Range{0, 6e6, true, "speed change", "mm/min"}, 1.0 / 60, " (mm/min / 60)");
  else if (c == "M204" && l.words.count('P')) s_.print_accel = Sourced{value(l, 'P', detail::kAccel), l.site.cite()};
  else if (c == "M208") limits(l);
  else if (c == "M669" || c == "M667" || c == "M665") kinematics(l);
  else if (c == "M143" || c == "M140" || c == "M563") heaters(l);
  else if (c == "M593") shaper(l);
  else if (c == "M955") s_.accelerometer = l.site.cite();
}

RrfState RrfReader::run() {
  std::istringstream in(firmware::read_config_file(path_));
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    std::string text = line.substr(0, line.find(';'));
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    text.erase(0, std::min(text.size(), text.find_first_not_of(" \t")));
    if (const auto l = rrf_parse(line, Site{path_, n, text})) dispatch(*l);
  }
  return s_;
}

// --- The profile ---------------------------------------------------------------------------------

Sourced need(const std::map<char, Sourced>& m, char a, const char* what, const std::string& path) {
  const auto it = m.find(a);
  if (it == m.end()) throw InputError(fmt::format("config.g sets no {} for {} ({})", what, a, what), path);
  return it->second;
}

void rrf_travel(MachineProfile& p, const RrfState& s, const std::string& path) {
  const char axes[] = {'X', 'Y', 'Z'};
  for (int i = 0; i < 3; ++i) {
    const char a = axes[i];
    const std::string name(1, static_cast<char>(std::tolower(a)));
    Sourced lo = s.lo.count(a) ? s.lo.at(a) : Sourced{0, "RepRapFirmware's default axis minimum 0 (Configuration.h)"};
    std::optional<Sourced> hi = s.hi.count(a) ? std::optional<Sourced>(s.hi.at(a)) : std::nullopt;
    if (s.kinematics_name == "delta" && a != 'Z') {
      if (!s.delta_radius) throw InputError("M665 gives no printable radius (B)", path);
      const double half = s.delta_radius->value / std::numbers::sqrt2;
      const std::string why = fmt::format(
          "{}: printable radius B {:g} mm; tunekit's travel is a box: the square "
          "inside that circle, B / sqrt(2) = {:.6g} mm",
          s.delta_radius->source, s.delta_radius->value, half);
      lo = Sourced{-half, why};
      hi = Sourced{half, why};
    } else if (s.kinematics_name == "delta" && !hi && s.delta_height) {
      hi = Sourced{s.delta_height->value, s.delta_height->source + " (homed height H)"};
    }
    if (!hi) throw InputError(fmt::format("config.g sets no maximum for {} (M208 {}... S0)", a, a), path);
    detail::set_axis(p, name, lo, *hi, need(s.feed, a, "maximum speed (M203)", path),
                     need(s.accel, a, "maximum acceleration (M201)", path));
  }
}

void rrf_extruder_and_print(MachineProfile& p, const RrfState& s, const std::string& path) {
  auto& e = p.extruder;
  const Sourced fe = need(s.feed, 'E', "maximum speed (M203)", path),
                ae = need(s.accel, 'E', "acceleration (M201)", path);
  detail::set_value(p, "extruder.max_velocity_mm_s", e.max_velocity_mm_s, fe.value, fe.source);
  detail::set_value(p, "extruder.max_accel_mm_s2", e.max_accel_mm_s2, ae.value,
                    ae.source + " (an extrude-only move is limited by M201 E)");
  detail::set_value(p, "extruder.filament_diameter_mm", e.filament_diameter_mm, 1.75,
                    "RepRapFirmware's default filament diameter 1.75 mm (Configuration.h DefaultFilamentDiameter)");
  detail::set_value(p, "extruder.nozzle_diameter_mm", e.nozzle_diameter_mm, 0.4,
                    "tunekit default: config.g does not hold the nozzle diameter; 0.4 mm, the stock nozzle of most "
                    "desktop printers (set nozzle_diameter_mm to yours)");
  detail::set_value(p, "extruder.max_extrude_only_distance_mm", e.max_extrude_only_distance_mm, 50,
                    "tunekit default: RepRapFirmware sets no limit here; protocols split feeds into moves of at "
                    "most 50 mm");
  const Sourced ax = need(s.accel, 'X', "acceleration (M201)", path), ay = need(s.accel, 'Y', "acceleration", path);
  const Sourced& xy = ax.value <= ay.value ? ax : ay;
  const Sourced pa = s.print_accel ? *s.print_accel
                                   : Sourced{xy.value,
                                             "no M204 P: RepRapFirmware's default print acceleration is "
                                             "above any M201 limit (Configuration.h), so M201 rules: " +
                                                 xy.source};
  detail::set_value(p, "print.max_accel_mm_s2", p.print.max_accel_mm_s2, std::min(pa.value, xy.value), pa.source);
  auto& st = p.state;
  detail::set_value(p, "firmware_state.max_accel_xy_mm_s2", st.max_accel_xy_mm_s2, xy.value, xy.source);
  detail::set_value(p, "firmware_state.max_accel_e_mm_s2", st.max_accel_e_mm_s2, ae.value, ae.source);
  if (s.jerk.count('X') && s.jerk.count('Y')) {
    const Sourced& j = s.jerk.at('X').value <= s.jerk.at('Y').value ? s.jerk.at('X') : s.jerk.at('Y');
    detail::set_value(p, "firmware_state.jerk_xy_mm_s", st.jerk_xy_mm_s, j.value, j.source);
  }
  if (s.steps.count('X') && s.steps.count('Y')) {
    detail::set_value(p, "firmware_state.steps_per_mm_x", st.steps_per_mm_x, s.steps.at('X').value,
                      s.steps.at('X').source);
    detail::set_value(p, "firmware_state.steps_per_mm_y", st.steps_per_mm_y, s.steps.at('Y').value,
                      s.steps.at('Y').source);
  }
}

void rrf_heaters_sensors(MachineProfile& p, const RrfState& s) {
  const auto limit = [&](int h, double fallback, const char* what) {
    const auto it = s.heater_limit.find(h);
    if (it != s.heater_limit.end()) return it->second;
    return Sourced{fallback, fmt::format("no M143 H{}: RepRapFirmware's default {} limit {:g} degC (Configuration.h)",
                                         h, what, fallback)};
  };
  const Sourced hot = limit(s.tool_heater, kRrfDefaultHotendLimit_c, "hot-end");
  detail::set_value(p, "temperature.hotend_max_c", p.temperature.hotend_max_c, hot.value, hot.source);
  const Sourced bed = s.bed_heater < 0 ? Sourced{1.0, "M140 H-1: no heated bed; 1 degC lets no bed heating pass"}
                                       : limit(s.bed_heater, kRrfDefaultBedLimit_c, "bed");
  detail::set_value(p, "temperature.bed_max_c", p.temperature.bed_max_c, bed.value, bed.source);
  if (s.shaper) {
    for (const char* axis : {"x", "y"}) {
      p.state.shaper[axis] = s.shaper->first;
      p.sources[std::string("firmware_state.shaper_") + axis] = s.shaper->second;
    }
  }
  if (s.accelerometer) {
    p.sensors.accelerometer = true;
    p.sources["sensors.accelerometer"] = *s.accelerometer;
  }
}

}  // namespace

MachineProfile profile_from_rrf(const std::string& path, const ProfileImportOptions& options) {
  const RrfState s = RrfReader(path).run();
  MachineProfile p;
  p.source_path = path;
  p.firmware = "rrf";
  p.sources["machine.firmware"] = path + ": a RepRapFirmware config.g";
  p.name = std::filesystem::path(path).parent_path().filename().string();
  if (p.name.empty() || p.name == "sys") p.name = std::filesystem::path(path).stem().string();
  p.sources["machine.name"] = "the configuration's folder name";
  p.kinematics = s.kinematics_name;
  p.sources["machine.kinematics"] =
      s.kinematics ? s.kinematics->source : "no M669 K: RepRapFirmware's default, cartesian";
  rrf_travel(p, s, path);
  rrf_extruder_and_print(p, s, path);
  rrf_heaters_sensors(p, s);
  detail::apply_sensor_options(p, options);
  detail::apply_common_defaults(p);
  detail::check_imported(p);
  return p;
}

}  // namespace tunekit::machine
