// A machine profile from Marlin's configuration: an M503 report (the settings in force, as the
// firmware prints them) or Configuration.h with Configuration_adv.h beside it (MarlinFirmware,
// Marlin 2.1, 2011-2026). What Marlin does with the values:
//  - a move without X/Y/Z steps (an extrude-only move) accelerates at the retract acceleration
//    M204 R (Marlin/src/module/planner.cpp, _populate_block: `if (!block->steps.a && !b && !c)
//    accel = retract_acceleration`); the per-axis M201 limits are applied only to the other moves.
//    tunekit takes the smaller of M204 R and M201 E, so that no feed exceeds either;
//  - the highest hot-end target is HEATER_0_MAXTEMP - HOTEND_OVERSHOOT and the highest bed target
//    BED_MAXTEMP - BED_OVERSHOOT (Marlin/src/module/temperature.h hotend_max_target, BED_MAX_TARGET);
//  - M203 is in mm/s, M201 and M204 in mm/s^2, M205 B in microseconds.
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

#include "marlin_header.hpp"
#include "profile_import_detail.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/text.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {
namespace {

using detail::Site;
using detail::Sourced;

std::string marlin_trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// --- Configuration.h ---------------------------------------------------------------------------

class MarlinHeader {
 public:
  explicit MarlinHeader(const std::string& path) : path_(path) {
    detail::read_marlin_defines(path, d_);
    const auto adv = std::filesystem::path(path).parent_path() / "Configuration_adv.h";
    if (std::filesystem::is_regular_file(adv)) detail::read_marlin_defines(adv.string(), d_);
  }
  bool enabled(const std::string& name) const { return detail::marlin_enabled(d_, name); }
  std::optional<Sourced> number(const std::string& name, const detail::Range& range) const {
    const auto it = d_.find(name);
    if (it == d_.end()) return std::nullopt;
    const double v = detail::eval_marlin_expression(d_, it->second.value, it->second.site);
    return Sourced{detail::checked(v, range, it->second.site, name), it->second.site.cite()};
  }
  Sourced required(const std::string& name, const detail::Range& range) const {
    if (auto v = number(name, range)) return *v;
    throw InputError(fmt::format("{} is not defined (Marlin's Configuration.h defines it)", name), path_);
  }
  /// Element `index` of a `{ a, b, c, e }` array define (the last for a shorter array, as
  /// Marlin repeats the last value for further extruders).
  Sourced element(const std::string& name, std::size_t index, const detail::Range& range) const {
    const auto it = d_.find(name);
    if (it == d_.end()) throw InputError(fmt::format("{} is not defined", name), path_);
    std::string v = marlin_trim(it->second.value);
    if (v.size() < 2 || v.front() != '{' || v.back() != '}')
      throw InputError(fmt::format("{} must be a list {{ X, Y, Z, E }}", name), it->second.site.where());
    std::vector<std::string> parts;
    std::stringstream ss(v.substr(1, v.size() - 2));
    for (std::string part; std::getline(ss, part, ',');) parts.push_back(part);
    if (parts.size() < 4) throw InputError(fmt::format("{} needs X, Y, Z and E values", name), it->second.site.where());
    const double x = detail::eval_marlin_expression(d_, parts[std::min(index, parts.size() - 1)], it->second.site);
    return {detail::checked(x, range, it->second.site, name), it->second.site.cite()};
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  detail::MarlinDefines d_;
};

// --- What both sources give ----------------------------------------------------------------------

/// Marlin's settings, each with its source; travel and heater limits are absent from M503.
struct MarlinSettings {
  std::string kinematics = "cartesian";
  std::string kinematics_source = "Marlin's default: cartesian (no COREXY, DELTA, ... defined)";
  Sourced steps[4], feed[4], accel[4];
  Sourced print_accel, retract_accel, min_segment_time_s, filament_dia;
  std::optional<Sourced> lo[3], hi[3];  ///< travel, mm
  std::optional<Sourced> hotend_max, bed_max, extrude_max_length;
  std::map<std::string, std::pair<std::string, std::string>> shaper;  ///< axis -> (value, source)
};

const char* const kAxes[] = {"x", "y", "z", "e"};

std::string marlin_default(const std::string& what) { return "Marlin's default (Configuration.h): " + what; }

void header_motion(const MarlinHeader& h, MarlinSettings& m) {
  for (std::size_t i = 0; i < 4; ++i) {
    m.steps[i] = h.element("DEFAULT_AXIS_STEPS_PER_UNIT", i, detail::kStepsPerMm);
    m.feed[i] = h.element("DEFAULT_MAX_FEEDRATE", i, detail::kVelocity);
    m.accel[i] = h.element("DEFAULT_MAX_ACCELERATION", i, detail::kAccel);
  }
  m.print_accel = h.required("DEFAULT_ACCELERATION", detail::kAccel);
  m.retract_accel = h.required("DEFAULT_RETRACT_ACCELERATION", detail::kAccel);
  auto seg = h.number("DEFAULT_MINSEGMENTTIME", detail::Range{0, 1e7, false, "time", "us"});
  m.min_segment_time_s = seg ? Sourced{seg->value * 1e-6, seg->source + " (us)"}
                             : Sourced{firmware::limits::kMarlinDefaultMinSegmentTime_s,
                                       "Marlin's default (Configuration_adv.h): DEFAULT_MINSEGMENTTIME 20000 us"};
  m.filament_dia = h.number("DEFAULT_NOMINAL_FILAMENT_DIA", detail::kDiameter)
                       .value_or(Sourced{1.75, marlin_default("DEFAULT_NOMINAL_FILAMENT_DIA 1.75")});
  if (h.enabled("PREVENT_LENGTHY_EXTRUDE")) m.extrude_max_length = h.number("EXTRUDE_MAXLENGTH", detail::kLength);
}

void header_kinematics(const MarlinHeader& h, MarlinSettings& m) {
  for (const char* other : {"COREXZ", "COREYZ", "COREYX", "COREZX", "COREZY", "MARKFORGED_XY", "MARKFORGED_YX",
                            "MORGAN_SCARA", "MP_SCARA", "AXEL_TPARA", "POLARGRAPH", "POLAR", "FOAMCUTTER_XYUV"})
    if (h.enabled(other))
      throw InputError(fmt::format("kinematics {} is not one tunekit supports (cartesian, corexy, delta)", other),
                       h.path());
  if (h.enabled("COREXY")) {
    m.kinematics = "corexy";
    m.kinematics_source = h.path() + ": COREXY is defined";
  }
  if (h.enabled("DELTA")) {
    m.kinematics = "delta";
    m.kinematics_source = h.path() + ": DELTA is defined";
    // PRINTABLE_RADIUS since Marlin 2.1.3, DELTA_PRINTABLE_RADIUS before.
    const auto printable = h.number("PRINTABLE_RADIUS", detail::kLength);
    const auto r = printable ? *printable : h.required("DELTA_PRINTABLE_RADIUS", detail::kLength);
    const double half = r.value / std::numbers::sqrt2;
    const std::string why = fmt::format(
        "printable radius {:g} mm; tunekit's travel is a box: the square inside "
        "that circle, radius / sqrt(2) = {:.6g} mm ({})",
        r.value, half, r.source);
    for (std::size_t i = 0; i < 2; ++i) m.lo[i] = Sourced{-half, why}, m.hi[i] = Sourced{half, why};
  }
  for (std::size_t i = m.kinematics == "delta" ? 2 : 0; i < 3; ++i) {
    const std::string a(1, static_cast<char>(std::toupper(kAxes[i][0])));
    m.lo[i] = h.required(a + "_MIN_POS", detail::kPosition);
    m.hi[i] = h.required(a + "_MAX_POS", detail::kPosition);
  }
}

void header_heaters_shaper(const MarlinHeader& h, MarlinSettings& m) {
  const auto hot = h.required("HEATER_0_MAXTEMP", detail::kTemperature);
  const auto over = h.number("HOTEND_OVERSHOOT", detail::Range{0, 1000, false, "temperature", "degC"})
                        .value_or(Sourced{15, marlin_default("HOTEND_OVERSHOOT 15")});
  m.hotend_max = Sourced{hot.value - over.value,
                         fmt::format("Marlin/src/module/temperature.h hotend_max_target: HEATER_0_MAXTEMP {:g} - "
                                     "HOTEND_OVERSHOOT {:g} = {:g} degC ({}; {})",
                                     hot.value, over.value, hot.value - over.value, hot.source, over.source)};
  if (const auto bed = h.number("BED_MAXTEMP", detail::kTemperature)) {
    const auto bo = h.number("BED_OVERSHOOT", detail::Range{0, 1000, false, "temperature", "degC"})
                        .value_or(Sourced{10, marlin_default("BED_OVERSHOOT 10")});
    m.bed_max = Sourced{bed->value - bo.value,
                        fmt::format("Marlin/src/module/temperature.h BED_MAX_TARGET: BED_MAXTEMP {:g} - BED_OVERSHOOT "
                                    "{:g} = {:g} degC ({}; {})",
                                    bed->value, bo.value, bed->value - bo.value, bed->source, bo.source)};
  }
  for (const char* axis : {"X", "Y"}) {
    if (!h.enabled(std::string("INPUT_SHAPING_") + axis)) continue;
    const auto f = h.required(std::string("SHAPING_FREQ_") + axis, detail::kFrequency);
    const auto z = h.required(std::string("SHAPING_ZETA_") + axis, detail::kFraction);
    m.shaper[core::lower(axis)] = {fmt::format("zv:{}:{}", f.value, z.value), f.source + "; " + z.source};
  }
}

MarlinSettings from_configuration_h(const std::string& path) {
  const MarlinHeader h(path);
  MarlinSettings m;
  header_motion(h, m);
  header_kinematics(h, m);
  header_heaters_shaper(h, m);
  return m;
}

// --- M503 ----------------------------------------------------------------------------------------

struct ReportLine {
  std::map<char, std::string> words;
  Site site;
};

/// The report's G-code lines by command ("M203"), the last of each (M593 by its axis: "M593 X").
std::map<std::string, ReportLine> read_report(const std::string& path) {
  std::map<std::string, ReportLine> out;
  std::istringstream in(firmware::read_config_file(path));
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    std::string t = marlin_trim(line);
    for (bool again = true; again;) {
      again = false;
      for (const char* prefix : {"Recv:", "echo:"})
        if (t.rfind(prefix, 0) == 0) t = marlin_trim(t.substr(std::string(prefix).size())), again = true;
    }
    t = marlin_trim(t.substr(0, t.find(';')));
    if (t.size() < 2 || (t[0] != 'M' && t[0] != 'G')) continue;
    std::istringstream words(t);
    std::string cmd, w;
    words >> cmd;
    ReportLine r{{}, Site{path, n, t}};
    while (words >> w) r.words[static_cast<char>(std::toupper(static_cast<unsigned char>(w[0])))] = w.substr(1);
    if (cmd == "M593") cmd += r.words.count('Y') && !r.words.count('X') ? " Y" : " X";
    out[cmd] = r;
  }
  return out;
}

class Report {
 public:
  explicit Report(const std::string& path) : path_(path), lines_(read_report(path)) {}
  const ReportLine* line(const std::string& cmd) const {
    const auto it = lines_.find(cmd);
    return it == lines_.end() ? nullptr : &it->second;
  }
  Sourced word(const std::string& cmd, char w, const detail::Range& range, const char* what) const {
    const auto* l = line(cmd);
    if (l == nullptr || !l->words.count(w))
      throw InputError(fmt::format("the M503 report has no {} {} ({})", cmd, w, what), path_);
    return {detail::parse_number(l->words.at(w), range, l->site, fmt::format("{} {}", cmd, w)), l->site.cite()};
  }
  std::optional<Sourced> maybe(const std::string& cmd, char w, const detail::Range& range) const {
    const auto* l = line(cmd);
    if (l == nullptr || !l->words.count(w)) return std::nullopt;
    return word(cmd, w, range, "");
  }

 private:
  std::string path_;
  std::map<std::string, ReportLine> lines_;
};

void report_shaper(const Report& r, MarlinSettings& m) {
  for (const char* axis : {"X", "Y"}) {
    const std::string cmd = std::string("M593 ") + axis;
    const auto f = r.maybe(cmd, 'F', detail::kFrequency);
    if (!f || !(f->value > 0)) continue;
    const auto d = r.maybe(cmd, 'D', detail::kFraction).value_or(Sourced{0.1, "no D: 0.1"});
    m.shaper[core::lower(axis)] = {fmt::format("zv:{}:{}", f->value, d.value), f->source};
  }
}

MarlinSettings from_m503(const std::string& path, const ProfileImportOptions& o) {
  const Report r(path);
  MarlinSettings m;
  const char* const names[] = {"X", "Y", "Z", "E"};
  for (std::size_t i = 0; i < 4; ++i) {
    m.steps[i] = r.word("M92", names[i][0], detail::kStepsPerMm, "steps per mm");
    m.feed[i] = r.word("M203", names[i][0], detail::kVelocity, "maximum feed rate, mm/s");
    m.accel[i] = r.word("M201", names[i][0], detail::kAccel, "maximum acceleration, mm/s^2");
  }
  m.print_accel = r.maybe("M204", 'P', detail::kAccel).value_or(Sourced{});
  if (!(m.print_accel.value > 0)) m.print_accel = r.word("M204", 'S', detail::kAccel, "print acceleration");
  m.retract_accel = r.word("M204", 'R', detail::kAccel, "retract acceleration");
  if (const auto b = r.maybe("M205", 'B', detail::Range{0, 1e7, false, "time", "us"}))
    m.min_segment_time_s = Sourced{b->value * 1e-6, b->source + " (B in us)"};
  else m.min_segment_time_s = Sourced{firmware::limits::kMarlinDefaultMinSegmentTime_s, marlin_default("20000 us")};
  m.filament_dia = r.maybe("M200", 'D', detail::kDiameter).value_or(Sourced{1.75, marlin_default("1.75 mm")});
  report_shaper(r, m);
  std::vector<std::string> missing;
  if (o.travel_mm.size() != 3) missing.push_back("the travel (--travel X,Y,Z in mm)");
  if (!(o.hotend_max_c > 0)) missing.push_back("the highest hot-end target (--hotend-max-c)");
  if (!(o.bed_max_c > 0)) missing.push_back("the highest bed target (--bed-max-c)");
  if (!missing.empty()) {
    std::string list;
    for (const auto& s : missing) list += (list.empty() ? "" : ", ") + s;
    throw InputError(fmt::format("an M503 report holds no travel and no heater limits: give {}, or import the "
                                 "printer's Configuration.h instead",
                                 list),
                     path);
  }
  const Site given{"command line", 0, ""};
  for (std::size_t i = 0; i < 3; ++i) {
    m.lo[i] = Sourced{0, "given on the command line (--travel, from 0)"};
    m.hi[i] = Sourced{detail::checked(o.travel_mm[i], detail::kLength, given, "--travel"),
                      "given on the command line (--travel)"};
  }
  m.hotend_max = Sourced{detail::checked(o.hotend_max_c, detail::kTemperature, given, "--hotend-max-c"),
                         "given on the command line (--hotend-max-c)"};
  m.bed_max = Sourced{detail::checked(o.bed_max_c, detail::kTemperature, given, "--bed-max-c"),
                      "given on the command line (--bed-max-c)"};
  return m;
}

// --- The profile ---------------------------------------------------------------------------------

void fill_axes_and_state(MachineProfile& p, const MarlinSettings& m) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (!m.lo[i] || !m.hi[i] || !(m.hi[i]->value > m.lo[i]->value))
      throw InputError(fmt::format("the {} axis has no travel (its maximum must exceed its minimum)", kAxes[i]),
                       p.source_path);
    detail::set_axis(p, kAxes[i], *m.lo[i], *m.hi[i], m.feed[i], m.accel[i]);
  }
  auto& st = p.state;
  detail::set_value(p, "firmware_state.steps_per_mm_x", st.steps_per_mm_x, m.steps[0].value, m.steps[0].source);
  detail::set_value(p, "firmware_state.steps_per_mm_y", st.steps_per_mm_y, m.steps[1].value, m.steps[1].source);
  detail::set_value(p, "firmware_state.min_segment_time_s", st.min_segment_time_s, m.min_segment_time_s.value,
                    m.min_segment_time_s.source);
  const Sourced& xy = m.accel[0].value <= m.accel[1].value ? m.accel[0] : m.accel[1];
  detail::set_value(p, "firmware_state.max_accel_xy_mm_s2", st.max_accel_xy_mm_s2, xy.value, xy.source);
  detail::set_value(p, "firmware_state.retract_accel_mm_s2", st.retract_accel_mm_s2, m.retract_accel.value,
                    m.retract_accel.source);
  detail::set_value(p, "firmware_state.max_accel_e_mm_s2", st.max_accel_e_mm_s2, m.accel[3].value, m.accel[3].source);
  for (const auto& [axis, v] : m.shaper) {
    st.shaper[axis] = v.first;
    p.sources["firmware_state.shaper_" + axis] = v.second;
  }
}

void fill_extruder(MachineProfile& p, const MarlinSettings& m) {
  auto& e = p.extruder;
  detail::set_value(p, "extruder.filament_diameter_mm", e.filament_diameter_mm, m.filament_dia.value,
                    m.filament_dia.source);
  detail::set_value(p, "extruder.nozzle_diameter_mm", e.nozzle_diameter_mm, 0.4,
                    "tunekit default: Marlin's configuration does not hold the nozzle diameter; 0.4 mm, the stock "
                    "nozzle of most desktop printers (set nozzle_diameter_mm to yours)");
  detail::set_value(p, "extruder.max_velocity_mm_s", e.max_velocity_mm_s, m.feed[3].value, m.feed[3].source);
  const bool r_lower = m.retract_accel.value <= m.accel[3].value;
  detail::set_value(p, "extruder.max_accel_mm_s2", e.max_accel_mm_s2, std::min(m.retract_accel.value, m.accel[3].value),
                    fmt::format("Marlin runs extrude-only moves at the retract acceleration (M204 R {:g}; "
                                "Marlin/src/module/planner.cpp: no X/Y/Z steps -> retract_acceleration); tunekit "
                                "takes the smaller of it and M201 E {:g}: {} ({})",
                                m.retract_accel.value, m.accel[3].value, r_lower ? "M204 R" : "M201 E",
                                r_lower ? m.retract_accel.source : m.accel[3].source));
  if (m.extrude_max_length)
    detail::set_value(p, "extruder.max_extrude_only_distance_mm", e.max_extrude_only_distance_mm,
                      m.extrude_max_length->value,
                      m.extrude_max_length->source + " (PREVENT_LENGTHY_EXTRUDE: longer extrusions are refused)");
  else
    detail::set_value(p, "extruder.max_extrude_only_distance_mm", e.max_extrude_only_distance_mm,
                      firmware::limits::kKlipperMaxExtrudeOnlyDistance_mm,
                      "tunekit default: Marlin sets no limit here; protocols split feeds into moves of at most 50 mm");
}

MachineProfile marlin_profile(const std::string& path, const MarlinSettings& m) {
  MachineProfile p;
  p.source_path = path;
  p.firmware = "marlin";
  p.sources["machine.firmware"] = path + ": a Marlin configuration";
  p.name = std::filesystem::path(path).parent_path().filename().string();
  if (p.name.empty()) p.name = std::filesystem::path(path).stem().string();
  p.sources["machine.name"] = "the configuration's folder name";
  p.kinematics = m.kinematics;
  p.sources["machine.kinematics"] = m.kinematics_source;
  fill_axes_and_state(p, m);
  fill_extruder(p, m);
  detail::set_value(p, "print.max_accel_mm_s2", p.print.max_accel_mm_s2, m.print_accel.value, m.print_accel.source);
  detail::set_value(p, "temperature.hotend_max_c", p.temperature.hotend_max_c, m.hotend_max->value,
                    m.hotend_max->source);
  if (m.bed_max)
    detail::set_value(p, "temperature.bed_max_c", p.temperature.bed_max_c, m.bed_max->value, m.bed_max->source);
  else
    detail::set_value(p, "temperature.bed_max_c", p.temperature.bed_max_c, 1.0,
                      "BED_MAXTEMP is not defined: the machine has no heated bed; 1 degC lets no bed heating pass "
                      "tunekit's safety check (a profile needs a positive number)");
  return p;
}

}  // namespace

MachineProfile profile_from_marlin(const std::string& path, const ProfileImportOptions& options) {
  const std::string text = firmware::read_config_file(path);
  const bool header = detect_config_format(text, path) == ConfigFormat::marlin_config;
  const MarlinSettings m = header ? from_configuration_h(path) : from_m503(path, options);
  MachineProfile p = marlin_profile(path, m);
  detail::apply_sensor_options(p, options);
  detail::apply_common_defaults(p);
  detail::check_imported(p);
  return p;
}

}  // namespace tunekit::machine
