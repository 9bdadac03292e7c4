// Klipper printer.cfg writer. The file is an INI dialect: `[section]` headers, `key: value`
// or `key = value` options at column 0, indented continuation lines, comments from the first
// `#` of a line (and `;` after a blank), and `[include FILE]` sections that Klipper reads in
// place (relative to the including file, globbed, sorted). It may end in a SAVE_CONFIG block.
//
// Precedence, as Klipper's klippy/configfile.py (v0.13) loads a file:
//  - the regular part (the body with its includes, expanded where they stand) is read in
//    order and a later option overrides an earlier one (configparser with strict=False);
//  - the SAVE_CONFIG block is recognized only by its exact header (AUTOSAVE_HEADER) with every
//    following line starting "#*# " (_find_autosave_data); otherwise it is ignored;
//  - every option of the block that the regular part also sets is commented out at load
//    (_strip_duplicates): the body and its includes win over the block.
// So a value is written where it takes effect: over its last definition in the body; after
// an include that sets it (the body's value then comes later and wins); in the block only when
// the regular part does not set it; else added to the body's section or a new one.
#include <glob.h>

#include <algorithm>
#include <cmath>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "export_writers.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "text_util.hpp"

namespace tunekit::firmware::detail {
namespace {

// klippy/configfile.py AUTOSAVE_HEADER, line by line.
constexpr const char* kAutosaveHeader1 = "#*# <---------------------- SAVE_CONFIG ---------------------->";
constexpr const char* kAutosaveHeader2 = "#*# DO NOT EDIT THIS BLOCK OR BELOW. The contents are auto-generated.";
constexpr const char* kAutosaveHeader3 = "#*#";

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

struct Opt {
  std::string name;  // lower case
  std::size_t line = 0;
  std::size_t value_begin = 0;  // byte offsets in the line text
  std::size_t value_end = 0;
  std::string value;
  std::string sep;  // ":" or "="
};

struct Section {
  std::string name;
  std::size_t header = 0;
  std::size_t last_content = 0;
  std::vector<Opt> opts;
};

/// One definition of an option in the regular part, in Klipper's reading order.
struct Definition {
  std::string section, option, value;
  std::string file;      // empty: the edited file itself
  std::size_t line = 0;  // 0-based
};

struct Doc {
  std::vector<Section> main;
  std::vector<Section> block;
  std::optional<std::size_t> header;         // first line of a valid AUTOSAVE_HEADER
  std::optional<std::size_t> ignored_block;  // a "#*#" block Klipper does not read
  std::vector<std::string> includes;
  std::vector<Definition> regular;  // body and includes, in reading order
  std::vector<std::string> include_problems;
};

/// Klipper's comment rule: everything from the first '#' goes (configfile.py _parse_config),
/// and configparser's inline ';' after a blank.
std::size_t comment_start(const std::string& t, std::size_t from) {
  for (std::size_t k = from; k < t.size(); ++k) {
    if (t[k] == '#') return k;
    if (t[k] == ';' && k > 0 && text::is_blank(t[k - 1])) return k;
  }
  return t.size();
}

/// Parses one line (already stripped of a block prefix of `offset` bytes) into the section
/// list. Returns the include spec when the line is an include header.
std::optional<std::string> parse_line(std::vector<Section>& secs, const std::string& full, std::size_t offset,
                                      std::size_t index) {
  const std::string t = full.substr(offset);
  const std::string tt = trim(t.substr(0, comment_start(t, 0)));
  if (tt.empty() || tt[0] == ';') return std::nullopt;
  if (t[0] == ' ' || t[0] == '\t') {  // continuation of a multi-line value
    if (!secs.empty()) secs.back().last_content = index;
    return std::nullopt;
  }
  if (t[0] == '[') {
    const auto close = tt.rfind(']');
    Section s;
    s.name = trim(tt.substr(1, close == std::string::npos || close == 0 ? std::string::npos : close - 1));
    s.header = index;
    s.last_content = index;
    if (s.name.rfind("include ", 0) == 0) {
      // An include ends the current buffer: the next options need a new section header.
      const std::string spec = trim(s.name.substr(8));
      s.name = "\x01include";
      secs.push_back(std::move(s));
      return spec;
    }
    secs.push_back(std::move(s));
    return std::nullopt;
  }
  if (secs.empty()) return std::nullopt;
  const auto sep = t.find_first_of(":=");
  if (sep == std::string::npos) return std::nullopt;
  Opt o;
  o.name = core::lower(trim(t.substr(0, sep)));
  o.sep = t.substr(sep, 1);
  o.line = index;
  std::size_t vb = sep + 1;
  while (vb < t.size() && text::is_blank(t[vb])) ++vb;
  std::size_t ve = std::max(vb, comment_start(t, vb));
  while (ve > vb && text::is_blank(t[ve - 1])) --ve;
  o.value_begin = offset + vb;
  o.value_end = offset + ve;
  o.value = t.substr(vb, ve - vb);
  secs.back().opts.push_back(o);
  secs.back().last_content = index;
  return std::nullopt;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::string cur;
  for (char c : text) {
    if (c == '\n') {
      if (!cur.empty() && cur.back() == '\r') cur.pop_back();
      lines.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) lines.push_back(cur);
  return lines;
}

/// Reads an included file's definitions (recursively, as configfile.py _resolve_include).
void read_include(const std::string& including, const std::string& spec, Doc& d, std::set<std::string>& visited) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(including).parent_path();
  const std::string pattern = (dir / spec).string();
  glob_t g{};
  std::vector<std::string> files;
  if (::glob(pattern.c_str(), 0, nullptr, &g) == 0)
    for (std::size_t i = 0; i < g.gl_pathc; ++i) files.emplace_back(g.gl_pathv[i]);
  ::globfree(&g);
  std::sort(files.begin(), files.end());
  const bool magic = spec.find_first_of("*?[") != std::string::npos;
  if (files.empty()) {
    if (!magic)
      d.include_problems.push_back(fmt::format(
          "{}: [include {}]: the file {} does not exist here; Klipper refuses to start with a missing include "
          "(\"Include file '...' does not exist\", klippy/configfile.py), and options it might set are not checked",
          including, spec, pattern));
    return;
  }
  for (const auto& f : files) {
    std::error_code ec;
    const std::string canon = fs::weakly_canonical(f, ec).string();
    if (visited.count(canon)) continue;
    std::string text;
    try {
      text = read_config_file(f);  // a regular ASCII-compatible file of bounded size
    } catch (const Error& e) {
      d.include_problems.push_back(fmt::format("{}: cannot read the included file {}: {}", including, f, e.message()));
      continue;
    }
    visited.insert(canon);
    const auto lines = split_lines(text);
    std::vector<Section> secs;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const std::size_t nsec = secs.size();
      const std::size_t nopt = secs.empty() ? 0 : secs.back().opts.size();
      const auto inc = parse_line(secs, lines[i], 0, i);
      if (inc) {
        read_include(f, *inc, d, visited);
        continue;
      }
      if (!secs.empty() && secs.size() == nsec && secs.back().opts.size() > nopt && secs.back().name != "\x01include") {
        const auto& o = secs.back().opts.back();
        d.regular.push_back({secs.back().name, o.name, o.value, f, i});
      }
    }
    visited.erase(canon);
  }
}

/// Klipper's _find_autosave_data on lines: the header's first line, when the block is valid.
std::optional<std::size_t> find_autosave(const LineEditor& ed, std::optional<std::size_t>& ignored) {
  for (std::size_t i = 1; i + 2 < ed.size(); ++i) {
    if (ed.line(i) != kAutosaveHeader1 || ed.line(i + 1) != kAutosaveHeader2 || ed.line(i + 2) != kAutosaveHeader3)
      continue;
    // "\n#*# " in the regular part, or any later line not prefixed "#*# " (blank lines only at
    // the very end, where Klipper strips them): the block is not read.
    bool ok = true;
    for (std::size_t j = 1; j < i; ++j)
      if (ed.line(j).rfind("#*# ", 0) == 0) ok = false;
    std::size_t last = ed.size();
    while (last > i + 3 && trim(ed.line(last - 1)).empty()) --last;
    for (std::size_t j = i + 3; j < last; ++j) {
      const std::string& t = ed.line(j);
      if (t.rfind("#*#", 0) != 0 || (t.size() >= 4 && t.rfind("#*# ", 0) != 0)) ok = false;
    }
    if (ok) return i;
    ignored = i;
    return std::nullopt;
  }
  for (std::size_t i = 0; i < ed.size(); ++i)
    if (ed.line(i).rfind("#*#", 0) == 0 && ed.line(i).find("SAVE_CONFIG") != std::string::npos) {
      ignored = i;
      break;
    }
  return std::nullopt;
}

Doc parse(const LineEditor& ed, const std::string& path) {
  Doc d;
  d.header = find_autosave(ed, d.ignored_block);
  const std::size_t body_end = d.header ? *d.header : ed.size();
  std::set<std::string> visited;
  std::error_code ec;
  visited.insert(std::filesystem::weakly_canonical(path, ec).string());
  for (std::size_t i = 0; i < body_end; ++i) {
    const std::size_t nsec = d.main.size();
    const std::size_t nopt = d.main.empty() ? 0 : d.main.back().opts.size();
    const auto inc = parse_line(d.main, ed.line(i), 0, i);
    if (inc) {
      d.includes.push_back(*inc);
      read_include(path, *inc, d, visited);
      continue;
    }
    if (!d.main.empty() && d.main.size() == nsec && d.main.back().opts.size() > nopt &&
        d.main.back().name != "\x01include") {
      const auto& o = d.main.back().opts.back();
      d.regular.push_back({d.main.back().name, o.name, o.value, "", i});
    }
  }
  if (d.header)
    for (std::size_t i = *d.header + 3; i < ed.size(); ++i) {
      const std::string& t = ed.line(i);
      if (t.rfind("#*#", 0) != 0) continue;
      const std::size_t off = (t.size() > 3 && t[3] == ' ') ? 4 : 3;
      parse_line(d.block, t, off, i);
    }
  return d;
}

struct Want {
  std::string section;
  std::string option;
  std::string value;
  bool numeric = false;
  double number = 0;
  int decimals = 0;
};

bool same_value(const Want& w, const std::string& existing) {
  if (w.numeric) return same_number(existing, w.number, w.decimals);
  return core::lower(trim(existing)) == core::lower(w.value);
}

const Opt* find_opt(const std::vector<Section>& secs, const std::string& section, const std::string& option,
                    const Section** owner = nullptr) {
  const Opt* found = nullptr;
  for (const auto& s : secs) {
    if (s.name != section) continue;
    for (const auto& o : s.opts)
      if (o.name == option) {
        found = &o;
        if (owner) *owner = &s;
      }
  }
  return found;
}

const Section* last_section(const std::vector<Section>& secs, const std::string& name) {
  const Section* found = nullptr;
  for (const auto& s : secs)
    if (s.name == name) found = &s;
  return found;
}

}  // namespace

namespace {

/// The options to set, in the order they are written: the advance (or Kalico's model), its
/// smoothing time, each axis' shaper.
std::vector<Want> klipper_wants(ExportFirmware fw, const CompensatorSettings& s) {
  std::vector<Want> wants;
  auto num = [&](const std::string& sec, const std::string& opt, double v, int dec) {
    wants.push_back({sec, opt, format_number(v, dec), true, v, dec});
  };
  if (s.pa_k_s && !s.kalico) num(s.klipper_extruder, "pressure_advance", *s.pa_k_s, kDecimalsK);
  if (s.kalico) {
    // Kalico's nonlinear model (KalicoAdvanceSetting): its options replace pressure_advance.
    wants.push_back({s.klipper_extruder, "pressure_advance_model", s.kalico->model, false, 0, 0});
    num(s.klipper_extruder, "linear_advance", s.kalico->linear_advance_s, kDecimalsKalico);
    num(s.klipper_extruder, "nonlinear_offset", s.kalico->nonlinear_offset_mm, kDecimalsKalico);
    num(s.klipper_extruder, "linearization_velocity", s.kalico->linearization_velocity_mm_s, kDecimalsKalico);
    if (s.kalico->time_offset_s)
      num(s.klipper_extruder, "pressure_advance_time_offset", *s.kalico->time_offset_s, kDecimalsKalico);
  }
  if (s.pa_smooth_s) num(s.klipper_extruder, "pressure_advance_smooth_time", *s.pa_smooth_s, kDecimalsSmooth);
  if (s.thermal)
    for (const auto& o : thermal_klipper_options(fw, *s.thermal))
      wants.push_back({s.klipper_extruder, o.option, o.value, o.numeric, o.number, o.decimals});
  for (const auto& [axis, sh] : s.shapers) {
    const std::string type = firmware_shaper_name(ExportFirmware::klipper, sh.type);
    wants.push_back({"input_shaper", "shaper_type_" + axis, type, false, 0, 0});
    num("input_shaper", "shaper_freq_" + axis, sh.freq_hz, kDecimalsFreq);
    num("input_shaper", "damping_ratio_" + axis, sh.damping, kDecimalsZeta);
  }
  return wants;
}

using NewSections = std::vector<std::pair<std::string, std::vector<std::string>>>;

/// New sections at the file's end: those of the SAVE_CONFIG block (as "#*# " lines) and those of
/// a file without one, each with one header.
void append_new_sections(LineEditor& ed, const NewSections& new_block_sections, const NewSections& new_file_sections) {
  std::vector<std::string> tail;
  const bool last_blank = ed.size() == 0 || trim(ed.line(ed.size() - 1)).empty();
  const bool last_block_blank = ed.size() > 0 && trim(ed.line(ed.size() - 1)) == "#*#";
  bool first = true;
  for (const auto& [sec, lines] : new_block_sections) {
    if (!(first && last_block_blank)) tail.push_back("#*#");
    tail.push_back("#*# [" + sec + "]");
    tail.insert(tail.end(), lines.begin(), lines.end());
    first = false;
  }
  first = true;
  for (const auto& [sec, lines] : new_file_sections) {
    if (!(first && last_blank)) tail.push_back("");
    tail.push_back("[" + sec + "]");
    tail.insert(tail.end(), lines.begin(), lines.end());
    first = false;
  }
  if (!tail.empty()) ed.insert_before(ed.size(), tail);
}

/// A nonlinear model does not read pressure_advance, and Klipper-style config checking refuses
/// an option nobody reads ("Option '...' is not valid in section", klippy/configfile.py
/// check_unused_options): the body's line is commented out.
void comment_out_pressure_advance(LineEditor& ed, const Doc& doc, const CompensatorSettings& s, ExportResult& r) {
  for (const auto& sec : doc.main)
    if (sec.name == s.klipper_extruder)
      for (const auto& o : sec.opts)
        if (o.name == "pressure_advance") {
          ed.replace(o.line, "#" + ed.line(o.line));
          r.changes.push_back({fmt::format("[{}] pressure_advance", s.klipper_extruder), o.value, "(commented out)",
                               o.line + 1, "section"});
        }
  if (find_opt(doc.block, s.klipper_extruder, "pressure_advance"))
    r.warnings.push_back(
        fmt::format("{}: the SAVE_CONFIG block sets [{}] pressure_advance, which Kalico's {} model "
                    "does not read: remove it there before restarting",
                    r.path, s.klipper_extruder, s.kalico->model));
}

/// The options of the heater's other controls, which the new control does not read: Klipper-style
/// config checking refuses an option nobody reads ("Option '...' is not valid in section",
/// klippy/configfile.py check_unused_options). Klipper's watermark reads max_delta, its PID pid_kp,
/// pid_ki, pid_kd (klippy/extras/heaters.py); Kalico's MPC the model's keys (heaters.py).
std::vector<std::string> stale_control_options(ExportFirmware fw, const ThermalExport& t) {
  static const std::vector<std::string> kPid = {"pid_kp", "pid_ki", "pid_kd"};
  static const std::vector<std::string> kMpc = {
      "heater_power",     "block_heat_capacity",         "sensor_responsiveness",
      "ambient_transfer", "fan_ambient_transfer",        "filament_heat_capacity",
      "filament_density", "filament_diameter",           "target_reach_time",
      "smoothing",        "min_ambient_change",          "steady_state_rate",
      "maximum_retract",  "filament_temperature_source", "ambient_temp_sensor",
      "cooling_fan"};
  std::vector<std::string> out = {"max_delta"};
  const bool mpc = fw == ExportFirmware::kalico && !t.kalico_pid;
  const auto& other = mpc ? kPid : kMpc;
  if (fw == ExportFirmware::kalico) out.insert(out.end(), other.begin(), other.end());
  return out;
}

/// Comments out the stale options of the heater's section, in the body and in the SAVE_CONFIG
/// block (where "#*# #option" is a comment once Klipper strips the block's prefix).
void comment_out_stale_control(LineEditor& ed, const Doc& doc, const CompensatorSettings& s, ExportResult& r) {
  const auto stale = stale_control_options(r.firmware, *s.thermal);
  const auto visit = [&](const std::vector<Section>& secs, bool block) {
    for (const auto& sec : secs) {
      if (sec.name != s.klipper_extruder) continue;
      for (const auto& o : sec.opts) {
        if (std::find(stale.begin(), stale.end(), o.name) == stale.end()) continue;
        const std::string& t = ed.line(o.line);
        ed.replace(o.line, block ? "#*# #" + t.substr(std::min<std::size_t>(4, t.size())) : "#" + t);
        r.changes.push_back({fmt::format("[{}] {}", s.klipper_extruder, o.name), o.value, "(commented out)", o.line + 1,
                             block ? "SAVE_CONFIG block" : "section"});
      }
    }
  };
  visit(doc.main, false);
  visit(doc.block, true);
}

/// The runtime commands that apply the same values without a restart.
std::string klipper_runtime_gcode(const CompensatorSettings& s) {
  std::string g;
  if (s.kalico) {
    // Kalico's runtime form (docs/Nonlinear_Pressure_Advance.md, "Setting values via G-Code";
    // extruder.py cmd_SET_PRESSURE_ADVANCE reads MODEL, ADVANCE, OFFSET, VELOCITY, TIME_OFFSET).
    g += "SET_PRESSURE_ADVANCE";
    if (s.klipper_extruder != "extruder") g += " EXTRUDER=" + s.klipper_extruder;
    g += " MODEL=" + s.kalico->model + " ADVANCE=" + format_number(s.kalico->linear_advance_s, kDecimalsKalico) +
         " OFFSET=" + format_number(s.kalico->nonlinear_offset_mm, kDecimalsKalico) +
         " VELOCITY=" + format_number(s.kalico->linearization_velocity_mm_s, kDecimalsKalico);
    if (s.kalico->time_offset_s) g += " TIME_OFFSET=" + format_number(*s.kalico->time_offset_s, kDecimalsKalico);
    if (s.pa_smooth_s) g += " SMOOTH_TIME=" + format_number(*s.pa_smooth_s, kDecimalsSmooth);
    g += "\n";
  } else if (s.pa_k_s || s.pa_smooth_s) {
    g += "SET_PRESSURE_ADVANCE";
    if (s.klipper_extruder != "extruder") g += " EXTRUDER=" + s.klipper_extruder;
    if (s.pa_k_s) g += " ADVANCE=" + format_number(*s.pa_k_s, kDecimalsK);
    if (s.pa_smooth_s) g += " SMOOTH_TIME=" + format_number(*s.pa_smooth_s, kDecimalsSmooth);
    g += "\n";
  }
  if (!s.shapers.empty()) {
    g += "SET_INPUT_SHAPER";
    for (const auto& [axis, sh] : s.shapers) {
      std::string a = axis;
      std::transform(a.begin(), a.end(), a.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
      g += fmt::format(" SHAPER_TYPE_{}={} SHAPER_FREQ_{}={} DAMPING_RATIO_{}={}", a,
                       firmware_shaper_name(ExportFirmware::klipper, sh.type), a,
                       format_number(sh.freq_hz, kDecimalsFreq), a, format_number(sh.damping, kDecimalsZeta));
    }
    g += "\n";
  }
  return g;
}

// Where write_klipper puts the values: the file being edited, its parse, the end of its body
// (before the SAVE_CONFIG header, after the blank line that precedes it, so that the block stays
// the file's tail) and the new sections, collected so that each gets one header.
struct KlipperPlacement {
  LineEditor& ed;
  const Doc& doc;
  ExportResult& r;
  std::size_t body_end = 0;
  NewSections new_block_sections, new_file_sections, new_body_sections;
};

// The lines collected for section `sec` (a new entry when it has none yet).
std::vector<std::string>& pending_lines(NewSections& list, const std::string& sec) {
  for (auto& [name, lines] : list)
    if (name == sec) return lines;
  list.emplace_back(sec, std::vector<std::string>{});
  return list.back().second;
}

// The body's last definition of w (in this file) is the one Klipper uses: edit it.
void edit_body_definition(KlipperPlacement& pl, const Want& w, const Definition& last, const Opt* in_main,
                          const std::string& key) {
  const Opt* target = nullptr;
  for (const auto& sec : pl.doc.main)
    if (sec.name == w.section)
      for (const auto& o : sec.opts)
        if (o.name == w.option && o.line == last.line) target = &o;
  if (!target) target = in_main;
  if (same_value(w, target->value)) return;
  const std::string& t = pl.ed.line(target->line);
  std::string prefix = t.substr(0, target->value_begin);
  if (target->value_begin == t.size() && !prefix.empty() && prefix.back() != ' ') prefix += ' ';
  pl.ed.replace(target->line, prefix + w.value + t.substr(target->value_end));
  pl.r.changes.push_back({key, target->value, w.value, target->line + 1, "section"});
}

// A value no section of the body sets: into the body's section of that name, else the block's,
// else a new section (in the block when the file has one).
void add_new_value(KlipperPlacement& pl, const Want& w, const std::string& key) {
  auto& ed = pl.ed;
  if (const Section* sec = last_section(pl.doc.main, w.section)) {
    std::string sep = ": ";
    if (!sec->opts.empty() && sec->opts.front().sep == "=") sep = " = ";
    ed.insert_before(sec->last_content + 1, {w.option + sep + w.value});
    pl.r.changes.push_back({key, "", w.value, sec->last_content + 1, "added to section"});
    return;
  }
  if (pl.doc.header) {
    if (const Section* sec = last_section(pl.doc.block, w.section)) {
      ed.insert_before(sec->last_content + 1, {"#*# " + w.option + " = " + w.value});
      pl.r.changes.push_back({key, "", w.value, sec->last_content + 1, "added to SAVE_CONFIG block"});
    } else {
      pending_lines(pl.new_block_sections, w.section).push_back("#*# " + w.option + " = " + w.value);
      pl.r.changes.push_back({key, "", w.value, ed.size(), "new section in SAVE_CONFIG block"});
    }
  } else {
    pending_lines(pl.new_file_sections, w.section).push_back(w.option + ": " + w.value);
    pl.r.changes.push_back({key, "", w.value, ed.size(), "new section"});
  }
}

// One value: edited where Klipper reads it, overridden after the includes when an included file
// sets it, or added.
void place_want(KlipperPlacement& pl, const Want& w) {
  const Doc& doc = pl.doc;
  ExportResult& r = pl.r;
  const std::string key = fmt::format("[{}] {}", w.section, w.option);
  const Opt* in_block = find_opt(doc.block, w.section, w.option);
  const Definition* last = nullptr;
  for (const auto& d : doc.regular)
    if (d.section == w.section && d.option == w.option) last = &d;
  const Opt* in_main = find_opt(doc.main, w.section, w.option);

  if (last && in_block)
    r.warnings.push_back(fmt::format(
        "{}:{}: the SAVE_CONFIG copy {} = {} is ignored by Klipper, which comments out every SAVE_CONFIG option "
        "that the file above (or an include) also sets (klippy/configfile.py _strip_duplicates); the value is "
        "written above the block, the copy is left as it is",
        r.path, in_block->line + 1, key, in_block->value));

  if (last && last->file.empty()) {
    edit_body_definition(pl, w, *last, in_main, key);
    return;
  }
  if (last) {
    // Set last by an included file: tunekit edits only this file, so the value goes at the
    // end of the body, after every include, where it overrides the included one.
    if (same_value(w, last->value)) return;
    r.warnings.push_back(fmt::format(
        "{}:{}: {} = {} is set in an included file; the new value is added at the end of {} (after the includes), "
        "where Klipper reads it last and uses it; the included line is left as it is",
        last->file, last->line + 1, key, last->value, r.path));
    pending_lines(pl.new_body_sections, w.section).push_back(w.option + ": " + w.value);
    r.changes.push_back({key, last->value, w.value, pl.body_end + 1, "override after includes"});
    return;
  }
  if (in_block) {
    // Only the block sets it: Klipper reads it there.
    if (same_value(w, in_block->value)) return;
    const std::string& t = pl.ed.line(in_block->line);
    pl.ed.replace(in_block->line, t.substr(0, in_block->value_begin) + w.value + t.substr(in_block->value_end));
    r.changes.push_back({key, in_block->value, w.value, in_block->line + 1, "SAVE_CONFIG block"});
    return;
  }
  if (std::any_of(pl.new_body_sections.begin(), pl.new_body_sections.end(),
                  [&](const auto& ns) { return ns.first == w.section; })) {
    pending_lines(pl.new_body_sections, w.section).push_back(w.option + ": " + w.value);
    r.changes.push_back({key, "", w.value, pl.body_end + 1, "override after includes"});
    return;
  }
  add_new_value(pl, w, key);
}

// The sections that override included files: at the end of the body before the SAVE_CONFIG
// block, or with the file's new sections when it has no block.
void insert_body_sections(KlipperPlacement& pl) {
  if (pl.new_body_sections.empty()) return;
  std::vector<std::string> lines;
  if (pl.body_end > 0 && !trim(pl.ed.line(pl.body_end - 1)).empty()) lines.push_back("");
  bool first = true;
  for (const auto& [sec, opts] : pl.new_body_sections) {
    if (!first) lines.push_back("");
    lines.push_back("[" + sec + "]");
    lines.insert(lines.end(), opts.begin(), opts.end());
    first = false;
  }
  if (pl.doc.header) pl.ed.insert_before(pl.body_end, lines);
  else
    pl.new_file_sections.insert(pl.new_file_sections.begin(), pl.new_body_sections.begin(), pl.new_body_sections.end());
}

}  // namespace

void write_klipper(ExportResult& r, const CompensatorSettings& s) {
  LineEditor ed(r.original);
  const Doc doc = parse(ed, r.path);

  const std::vector<Want> wants = klipper_wants(r.firmware, s);

  for (const auto& p : doc.include_problems) r.warnings.push_back(p);
  if (doc.ignored_block)
    r.warnings.push_back(fmt::format(
        "{}:{}: this SAVE_CONFIG block is not read by Klipper (its header is not exactly Klipper's, or a line after "
        "it does not start with '#*# '; klippy/configfile.py _find_autosave_data): values are written above it",
        r.path, *doc.ignored_block + 1));
  KlipperPlacement pl{ed, doc, r, doc.header ? *doc.header : ed.size(), {}, {}, {}};
  if (doc.header) {
    while (pl.body_end > 0 && trim(ed.line(pl.body_end - 1)).empty()) --pl.body_end;
  }
  for (const auto& w : wants) place_want(pl, w);
  insert_body_sections(pl);
  append_new_sections(ed, pl.new_block_sections, pl.new_file_sections);

  if (s.kalico) comment_out_pressure_advance(ed, doc, s, r);
  if (s.thermal) comment_out_stale_control(ed, doc, s, r);
  r.updated = ed.render();
  r.diff = ed.unified_diff(r.path);

  r.gcode = klipper_runtime_gcode(s);
  if (s.thermal) r.gcode += thermal_klipper_gcode(r.firmware, *s.thermal, s.klipper_extruder);
  if (s.shapers.count("z"))
    r.notes.push_back(
        "shaper_type_z, shaper_freq_z and damping_ratio_z are read by Klipper since its Z-axis input shaper "
        "(D. Butyugin, Klipper, 4 October 2025); an older Klipper refuses to start on them above the SAVE_CONFIG "
        "block and ignores them inside it");
  if (r.updated != r.original)
    r.notes.push_back(r.gcode.empty()
                          ? "Klipper reads printer.cfg only at start-up: send RESTART after writing (a "
                            "heater's PID gains have no run-time command)"
                          : "Klipper reads printer.cfg only at start-up: send RESTART after writing (or the "
                            "G-code above to apply the values now without a restart)");
}

void validate_kalico(const KalicoAdvanceSetting& k, std::vector<std::string>& bad) {
  namespace L = tunekit::firmware::limits;
  const bool known = std::any_of(std::begin(L::kKalicoAdvanceModels), std::end(L::kKalicoAdvanceModels),
                                 [&](const char* m) { return k.model == m; });
  if (!known || k.model == "linear")
    bad.push_back(
        fmt::format("Kalico's nonlinear pressure_advance_model is tanh or recipr (klippy/kinematics/extruder.py), "
                    "not '{}'",
                    k.model));
  if (!std::isfinite(k.linear_advance_s) || k.linear_advance_s < L::kKalicoLinearAdvanceMin_s)
    bad.push_back(fmt::format("Kalico's linear_advance must be a number >= 0 (extruder.py minval=0.), not {}",
                              k.linear_advance_s));
  if (!std::isfinite(k.nonlinear_offset_mm) || k.nonlinear_offset_mm < L::kKalicoNonlinearOffsetMin_mm)
    bad.push_back(fmt::format("Kalico's nonlinear_offset must be a number >= 0 (extruder.py minval=0.), not {}",
                              k.nonlinear_offset_mm));
  if (!std::isfinite(k.linearization_velocity_mm_s) || k.linearization_velocity_mm_s < 0 ||
      (k.nonlinear_offset_mm > 0 && !(k.linearization_velocity_mm_s > 0)))
    bad.push_back(
        fmt::format("Kalico's linearization_velocity must be above 0 when nonlinear_offset is set "
                    "(extruder.py above=0.), not {}",
                    k.linearization_velocity_mm_s));
  if (k.time_offset_s &&
      !(*k.time_offset_s >= L::kKalicoTimeOffsetMin_s && *k.time_offset_s <= L::kKalicoTimeOffsetMax_s))
    bad.push_back(
        fmt::format("Kalico accepts pressure_advance_time_offset from {} to {} s (extruder.py); {} is out of range",
                    L::kKalicoTimeOffsetMin_s, L::kKalicoTimeOffsetMax_s, *k.time_offset_s));
}

}  // namespace tunekit::firmware::detail
