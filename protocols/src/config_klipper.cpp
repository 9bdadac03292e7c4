// Klipper printer.cfg writer. The file is an INI dialect: `[section]` headers, `key: value`
// or `key = value` options at column 0, indented continuation lines, `#`/`;` comments, and
// `[include FILE]` sections. It may end in a SAVE_CONFIG block (every line prefixed `#*#`)
// whose options override the same options above it. A value is therefore written where it
// takes effect: in the block when the block sets it, else in the section that sets it, else
// added to the last instance of its section, else added to the block, else a new section.
#include <algorithm>
#include <cctype>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "export_writers.hpp"
#include "tunekit/protocols/config_edit.hpp"
#include "text_util.hpp"

namespace tunekit::protocols::detail {
namespace {

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

struct Doc {
  std::vector<Section> main;
  std::vector<Section> block;
  std::optional<std::size_t> marker;  // line of "#*# <--- SAVE_CONFIG --->"
  std::vector<std::string> includes;
};

bool is_marker(const std::string& t) { return t.rfind("#*#", 0) == 0 && t.find("SAVE_CONFIG") != std::string::npos; }

/// Parses one logical line (already stripped of a block prefix of `offset` bytes) into the
/// section list.
void parse_line(std::vector<Section>& secs, std::vector<std::string>* includes, const std::string& full,
                std::size_t offset, std::size_t index) {
  const std::string t = full.substr(offset);
  const std::string tt = trim(t);
  if (tt.empty() || tt[0] == '#' || tt[0] == ';') return;
  if (t[0] == ' ' || t[0] == '\t') {  // continuation of a multi-line value
    if (!secs.empty()) secs.back().last_content = index;
    return;
  }
  if (t[0] == '[') {
    const auto close = t.find(']');
    Section s;
    s.name = trim(t.substr(1, close == std::string::npos ? std::string::npos : close - 1));
    s.header = index;
    s.last_content = index;
    if (includes && s.name.rfind("include ", 0) == 0) includes->push_back(trim(s.name.substr(8)));
    secs.push_back(std::move(s));
    return;
  }
  if (secs.empty()) return;
  const auto sep = t.find_first_of(":=");
  if (sep == std::string::npos) return;
  Opt o;
  o.name = text::lower(trim(t.substr(0, sep)));
  o.sep = t.substr(sep, 1);
  o.line = index;
  std::size_t vb = sep + 1;
  while (vb < t.size() && (t[vb] == ' ' || t[vb] == '\t')) ++vb;
  std::size_t ve = t.size();
  for (std::size_t k = vb; k < t.size(); ++k) {
    if ((t[k] == '#' || t[k] == ';') && k > 0 && (t[k - 1] == ' ' || t[k - 1] == '\t')) {
      ve = k;
      break;
    }
  }
  while (ve > vb && (t[ve - 1] == ' ' || t[ve - 1] == '\t')) --ve;
  o.value_begin = offset + vb;
  o.value_end = offset + ve;
  o.value = t.substr(vb, ve - vb);
  secs.back().opts.push_back(o);
  secs.back().last_content = index;
}

Doc parse(const LineEditor& ed) {
  Doc d;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    const std::string& t = ed.line(i);
    if (!d.marker && is_marker(t)) {
      d.marker = i;
      continue;
    }
    if (!d.marker) {
      parse_line(d.main, &d.includes, t, 0, i);
    } else {
      if (t.rfind("#*#", 0) != 0) continue;
      const std::size_t off = (t.size() > 3 && t[3] == ' ') ? 4 : 3;
      parse_line(d.block, nullptr, t, off, i);
    }
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
  return text::lower(trim(existing)) == text::lower(w.value);
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

void write_klipper(ExportResult& r, const CompensatorSettings& s) {
  LineEditor ed(r.original);
  const Doc doc = parse(ed);

  std::vector<Want> wants;
  auto num = [&](const std::string& sec, const std::string& opt, double v, int dec) {
    wants.push_back({sec, opt, format_number(v, dec), true, v, dec});
  };
  if (s.pa_k_s) num(s.klipper_extruder, "pressure_advance", *s.pa_k_s, kDecimalsK);
  if (s.pa_smooth_s) num(s.klipper_extruder, "pressure_advance_smooth_time", *s.pa_smooth_s, kDecimalsSmooth);
  for (const auto& [axis, sh] : s.shapers) {
    const std::string type = firmware_shaper_name(ExportFirmware::klipper, sh.type);
    wants.push_back({"input_shaper", "shaper_type_" + axis, type, false, 0, 0});
    num("input_shaper", "shaper_freq_" + axis, sh.freq_hz, kDecimalsFreq);
    num("input_shaper", "damping_ratio_" + axis, sh.damping, kDecimalsZeta);
  }

  // New sections are collected so that each gets one header.
  std::vector<std::pair<std::string, std::vector<std::string>>> new_block_sections, new_file_sections;
  auto pending = [](auto& list, const std::string& sec) -> std::vector<std::string>& {
    for (auto& [name, lines] : list)
      if (name == sec) return lines;
    list.emplace_back(sec, std::vector<std::string>{});
    return list.back().second;
  };
  bool warned_includes = false;

  for (const auto& w : wants) {
    const std::string key = fmt::format("[{}] {}", w.section, w.option);
    const Opt* in_block = find_opt(doc.block, w.section, w.option);
    const Opt* in_main = find_opt(doc.main, w.section, w.option);
    if (in_block) {
      if (in_main && !same_value(w, in_main->value))
        r.warnings.push_back(fmt::format("{}:{}: {} = {} is overridden by the SAVE_CONFIG block, where the new value "
                                         "is written; the line above is left as it is",
                                         r.path, in_main->line + 1, key, in_main->value));
      if (same_value(w, in_block->value)) continue;
      const std::string& t = ed.line(in_block->line);
      ed.replace(in_block->line, t.substr(0, in_block->value_begin) + w.value + t.substr(in_block->value_end));
      r.changes.push_back({key, in_block->value, w.value, in_block->line + 1, "SAVE_CONFIG block"});
      continue;
    }
    if (in_main) {
      if (same_value(w, in_main->value)) continue;
      const std::string& t = ed.line(in_main->line);
      std::string prefix = t.substr(0, in_main->value_begin);
      if (in_main->value_begin == t.size() && !prefix.empty() && prefix.back() != ' ') prefix += ' ';
      ed.replace(in_main->line, prefix + w.value + t.substr(in_main->value_end));
      r.changes.push_back({key, in_main->value, w.value, in_main->line + 1, "section"});
      continue;
    }
    if (const Section* sec = last_section(doc.main, w.section)) {
      std::string sep = ": ";
      if (!sec->opts.empty() && sec->opts.front().sep == "=") sep = " = ";
      ed.insert_before(sec->last_content + 1, {w.option + sep + w.value});
      r.changes.push_back({key, "", w.value, sec->last_content + 1, "added to section"});
      continue;
    }
    if (!doc.includes.empty() && !warned_includes) {
      warned_includes = true;
      r.warnings.push_back(fmt::format(
          "{}: some sections are not in this file (it includes {}); the values written here come after the includes "
          "and override them",
          r.path, fmt::join(doc.includes, ", ")));
    }
    if (doc.marker) {
      if (const Section* sec = last_section(doc.block, w.section)) {
        ed.insert_before(sec->last_content + 1, {"#*# " + w.option + " = " + w.value});
        r.changes.push_back({key, "", w.value, sec->last_content + 1, "added to SAVE_CONFIG block"});
      } else {
        pending(new_block_sections, w.section).push_back("#*# " + w.option + " = " + w.value);
        r.changes.push_back({key, "", w.value, ed.size(), "new section in SAVE_CONFIG block"});
      }
    } else {
      pending(new_file_sections, w.section).push_back(w.option + ": " + w.value);
      r.changes.push_back({key, "", w.value, ed.size(), "new section"});
    }
  }

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

  r.updated = ed.render();
  r.diff = ed.unified_diff(r.path);

  // Runtime commands with the same values.
  std::string g;
  if (s.pa_k_s || s.pa_smooth_s) {
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
                       firmware_shaper_name(ExportFirmware::klipper, sh.type), a, format_number(sh.freq_hz, kDecimalsFreq), a,
                       format_number(sh.damping, kDecimalsZeta));
    }
    g += "\n";
  }
  r.gcode = g;
}

}  // namespace tunekit::protocols::detail
