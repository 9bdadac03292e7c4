// RepRapFirmware config.g writer. The file is G-code run at start-up: `M572 D<drive> S<s>`
// sets pressure advance, `M593 P"<type>" F<hz> S<zeta>` the (single) input shaper. Existing
// commands get their parameter values rewritten in place (other parameters and the comment
// after ';' stay); missing ones are added after the drive configuration block.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <cctype>
#include <optional>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "text_util.hpp"

namespace tunekit::firmware::detail {
namespace {

struct Command {
  std::string code;  // upper case, e.g. "M572"
  std::size_t args_begin = 0;
  std::size_t code_end = 0;  // start of the ';' comment, or the line length
};

std::optional<Command> parse_command(const std::string& t) {
  std::size_t p = 0;
  while (p < t.size() && text::is_blank(t[p])) ++p;
  if (p >= t.size()) return std::nullopt;
  const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(t[p])));
  if (letter != 'M' && letter != 'G') return std::nullopt;
  std::size_t q = p + 1;
  while (q < t.size() && (std::isdigit(static_cast<unsigned char>(t[q])) || t[q] == '.')) ++q;
  if (q == p + 1) return std::nullopt;
  Command c;
  c.code = std::string(1, letter) + t.substr(p + 1, q - p - 1);
  c.args_begin = q;
  bool quoted = false;
  c.code_end = t.size();
  for (std::size_t k = q; k < t.size(); ++k) {
    if (t[k] == '"') quoted = !quoted;
    if (!quoted && t[k] == ';') {
      c.code_end = k;
      break;
    }
  }
  return c;
}

struct ParamPos {
  std::size_t value_begin = 0;
  std::size_t value_end = 0;
};

std::optional<ParamPos> find_param(const std::string& t, const Command& c, char letter) {
  bool quoted = false;
  for (std::size_t k = c.args_begin; k < c.code_end; ++k) {
    if (t[k] == '"') quoted = !quoted;
    if (quoted) continue;
    if (std::toupper(static_cast<unsigned char>(t[k])) == letter && (k == c.args_begin || text::is_blank(t[k - 1]))) {
      ParamPos p;
      p.value_begin = k + 1;
      std::size_t e = k + 1;
      bool q = false;
      while (e < c.code_end && (q || !text::is_blank(t[e]))) {
        if (t[e] == '"') q = !q;
        ++e;
      }
      p.value_end = e;
      return p;
    }
  }
  return std::nullopt;
}

/// Sets parameter `letter` to `value` in line `t` (appending it to the command when absent).
std::string set_param(const std::string& t, char letter, const std::string& value) {
  const auto c = parse_command(t);
  if (!c) return t;
  if (const auto p = find_param(t, *c, letter)) return t.substr(0, p->value_begin) + value + t.substr(p->value_end);
  std::size_t end = c->code_end;
  while (end > c->args_begin && text::is_blank(t[end - 1])) --end;
  return t.substr(0, end) + " " + std::string(1, letter) + value + t.substr(end);
}

std::string param_value(const std::string& t, char letter) {
  const auto c = parse_command(t);
  if (!c) return {};
  const auto p = find_param(t, *c, letter);
  return p ? t.substr(p->value_begin, p->value_end - p->value_begin) : std::string();
}

std::vector<std::string> split_colon(const std::string& v) {
  std::vector<std::string> out;
  std::size_t b = 0;
  for (;;) {
    const auto e = v.find(':', b);
    out.push_back(v.substr(b, e == std::string::npos ? std::string::npos : e - b));
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return out;
}

/// Position of `drive` in a colon-separated drive list ("0:1"), or -1.
int index_in_list(const std::string& list, const std::string& drive) {
  const auto items = split_colon(list);
  for (std::size_t i = 0; i < items.size(); ++i)
    if (items[i] == drive) return static_cast<int>(i);
  return -1;
}

bool is_drive_setup(const std::string& code) {
  static const char* codes[] = {"M584", "M350", "M92", "M906", "M566", "M203", "M201", "M84"};
  return std::any_of(std::begin(codes), std::end(codes), [&](const char* k) { return code == k; });
}

/// Where config.g's lines stand: the M572 of the drive, the M593, the last drive setup command
/// (new lines go after it) and the first M501.
struct RrfLines {
  std::optional<std::size_t> m572, m593, anchor, m501;
};

RrfLines find_rrf_lines(const LineEditor& ed, const std::string& drive) {
  RrfLines at;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    const auto c = parse_command(ed.line(i));
    if (!c) continue;
    if (c->code == "M572") {
      const std::string d = param_value(ed.line(i), 'D');
      if (d == drive || index_in_list(d, drive) >= 0) at.m572 = i;
    }
    if (c->code == "M593") at.m593 = i;
    if (is_drive_setup(c->code)) at.anchor = i;
    if (c->code == "M501" && !at.m501) at.m501 = i;
  }
  return at;
}

/// The config-override.g beside config.g at `config_path` (RepRapFirmware's M500 writes it, M501
/// runs it): its path, and its lines (nullopt when there is none).
std::string config_override_path(const std::string& config_path) {
  return (std::filesystem::path(config_path).parent_path() / "config-override.g").string();
}

std::optional<LineEditor> read_config_override(const std::string& config_path) {
  const std::string over = config_override_path(config_path);
  std::error_code ec;
  if (!std::filesystem::exists(over, ec)) return std::nullopt;
  return LineEditor(read_config_file(over));
}

/// Precedence: config.g's M501 runs config-override.g (GCodes2.cpp case 501) where it stands,
/// so a command there overrides the same command in config.g before the M501. RRF's M500
/// writes heater, kinematics, probe, tool and workplace values only (GCodes.cpp
/// WriteConfigOverrideFile), never M572/M593: such lines there were added by hand. InputError
/// for one that would override a value written here.
void check_config_override(const ExportResult& r, const CompensatorSettings& s, const RrfLines& at,
                           const std::string& drive) {
  if (!at.m501) return;
  const auto override_file = read_config_override(r.path);
  if (!override_file) return;
  const LineEditor& oe = *override_file;
  for (std::size_t i = 0; i < oe.size(); ++i) {
    const auto c = parse_command(oe.line(i));
    if (!c) continue;
    const bool pa = c->code == "M572" && s.pa_k_s && param_value(oe.line(i), 'D') == drive;
    const bool is = c->code == "M593" && !s.shapers.empty();
    if (!pa && !is) continue;
    const std::optional<std::size_t>& mine = pa ? at.m572 : at.m593;
    if (mine && *mine > *at.m501) continue;  // config.g's own line runs after config-override.g
    throw InputError(fmt::format(
        "{}:{}: '{}' in config-override.g is run by M501 (config.g line {}) after config.g's own {} and would "
        "override the value written here; remove that line from config-override.g (RepRapFirmware's M500 never "
        "writes {}, so it was added by hand) and export again",
        config_override_path(r.path), i + 1, oe.line(i), *at.m501 + 1, c->code, c->code));
  }
}

/// Pressure advance: the drive's M572 edited (its entry of a drive list), or a new line.
void write_rrf_advance(ExportResult& r, LineEditor& ed, const CompensatorSettings& s, const RrfLines& at,
                       const std::string& drive, std::vector<std::string>& new_lines) {
  const std::string k = format_number(*s.pa_k_s, kDecimalsK);
  if (!at.m572) {
    new_lines.push_back(fmt::format("M572 D{} S{} ; pressure advance (s)", drive, k));
    r.changes.push_back({"M572 D" + drive + " S", "", k, 0, "new line"});
    return;
  }
  const std::size_t line = *at.m572;
  const std::string& t = ed.line(line);
  const std::string old = param_value(t, 'S');
  const std::string dlist = param_value(t, 'D');
  const int pos = index_in_list(dlist, drive);
  if (dlist.find(':') != std::string::npos && pos >= 0) {
    // "M572 D0:1 S0.2:0.3" (GCodes2.cpp case 572: one S per listed drive, or one S for all):
    // only this drive's entry changes, the others keep theirs.
    std::vector<std::string> drives = split_colon(dlist), vals = split_colon(old);
    if (vals.size() == 1) vals.assign(drives.size(), vals[0]);
    if (vals.size() == drives.size() && !same_number(vals[static_cast<std::size_t>(pos)], *s.pa_k_s, kDecimalsK)) {
      const std::string before = vals[static_cast<std::size_t>(pos)];
      vals[static_cast<std::size_t>(pos)] = k;
      std::string joined;
      for (std::size_t q = 0; q < vals.size(); ++q) joined += (q ? ":" : "") + vals[q];
      ed.replace(line, set_param(t, 'S', joined));
      r.changes.push_back({"M572 D" + drive + " S", before, k, line + 1, "command (drive list)"});
    } else if (vals.size() != drives.size()) {
      r.warnings.push_back(fmt::format("{}:{}: M572 D{} S{}: the S list does not match the drives; left as it is",
                                       r.path, line + 1, dlist, old));
    }
  } else if (!same_number(old, *s.pa_k_s, kDecimalsK)) {
    ed.replace(line, set_param(t, 'S', k));
    r.changes.push_back({"M572 D" + drive + " S", old, k, line + 1, "command"});
  }
}

/// Input shaping: the M593 line's P, F and S edited where they differ, or a new line.
void write_rrf_shaper(ExportResult& r, LineEditor& ed, const ShaperSetting& sh, const RrfLines& at,
                      std::vector<std::string>& new_lines) {
  const std::string type = firmware_shaper_name(ExportFirmware::rrf, sh.type);
  const std::string f = format_number(sh.freq_hz, kDecimalsFreq);
  const std::string z = format_number(sh.damping, kDecimalsZeta);
  if (!at.m593) {
    new_lines.push_back(fmt::format("M593 P\"{}\" F{} S{} ; input shaping (Hz, damping ratio)", type, f, z));
    r.changes.push_back({"M593", "", fmt::format("P\"{}\" F{} S{}", type, f, z), 0, "new line"});
    return;
  }
  const std::size_t line = *at.m593;
  std::string t = ed.line(line);
  const std::string old_p = param_value(t, 'P'), old_f = param_value(t, 'F'), old_s = param_value(t, 'S');
  std::string bare_p = old_p;
  bare_p.erase(std::remove(bare_p.begin(), bare_p.end(), '"'), bare_p.end());
  if (core::lower(bare_p) != type) {
    t = set_param(t, 'P', "\"" + type + "\"");
    r.changes.push_back({"M593 P", old_p, "\"" + type + "\"", line + 1, "command"});
  }
  if (!same_number(old_f, sh.freq_hz, kDecimalsFreq)) {
    t = set_param(t, 'F', f);
    r.changes.push_back({"M593 F", old_f, f, line + 1, "command"});
  }
  if (!same_number(old_s, sh.damping, kDecimalsZeta)) {
    t = set_param(t, 'S', z);
    r.changes.push_back({"M593 S", old_s, z, line + 1, "command"});
  }
  ed.replace(line, t);
}

/// The heater's M307 line, and the M950 that creates the heater (M307 must follow it).
struct RrfHeaterLines {
  std::optional<std::size_t> m307, m950;
};

RrfHeaterLines find_heater_lines(const LineEditor& ed, const std::string& heater) {
  RrfHeaterLines at;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    const auto c = parse_command(ed.line(i));
    if (!c) continue;
    if (c->code == "M307" && param_value(ed.line(i), 'H') == heater) at.m307 = i;
    if (c->code == "M950" && param_value(ed.line(i), 'H') == heater) at.m950 = i;
  }
  return at;
}

/// The heater model: the heater's M307 edited (R, K, D, E; S, B and V kept) or a new line after its
/// M950. RRF's M500 writes M307 into config-override.g (GCodes.cpp WriteConfigOverrideFile), which
/// M501 runs after config.g's line: said when that file holds one for this heater.
void write_rrf_thermal(ExportResult& r, LineEditor& ed, const CompensatorSettings& s) {
  const std::string h = std::to_string(s.thermal->rrf_heater);
  const RrfHeaterLines at = find_heater_lines(ed, h);
  const RrfM307Values v = rrf_m307_values(*s.thermal);
  const std::pair<char, std::string> params[] = {{'R', v.r}, {'K', v.k}, {'D', v.d}, {'E', v.e}};
  if (at.m307) {
    std::string t = ed.line(*at.m307);
    for (const auto& [letter, value] : params) {
      const std::string old = param_value(t, letter);
      if (old == value) continue;
      t = set_param(t, letter, value);
      r.changes.push_back({fmt::format("M307 H{} {}", h, letter), old, value, *at.m307 + 1, "command"});
    }
    ed.replace(*at.m307, t);
  } else {
    if (!at.m950)
      throw InputError(fmt::format("config.g creates no heater {} (no 'M950 H{}' line): the heater model is written "
                                   "after the heater is created; choose the heater with --heater",
                                   h, h),
                       r.path);
    const std::string line = fmt::format("M307 H{} R{} K{} D{} E{} S{} B0 ; heater model (K/s, K/s at 100 K, s)", h,
                                         v.r, v.k, v.d, v.e, format_number(s.thermal->rrf_max_pwm, 2));
    ed.insert_before(*at.m950 + 1, {line});
    r.changes.push_back({fmt::format("M307 H{}", h), "", line.substr(0, line.find(" ;")), *at.m950 + 2, "new line"});
  }
  const auto override_file = read_config_override(r.path);
  if (!override_file) return;
  const LineEditor& oe = *override_file;
  for (std::size_t i = 0; i < oe.size(); ++i) {
    const auto c = parse_command(oe.line(i));
    if (c && c->code == "M307" && param_value(oe.line(i), 'H') == h)
      r.warnings.push_back(fmt::format(
          "{}:{}: config-override.g holds '{}' (RepRapFirmware's M500 writes it), which M501 runs after config.g: send "
          "the G-code below and then M500 so that it holds the new model too",
          config_override_path(r.path), i + 1, oe.line(i)));
  }
}

}  // namespace

void write_rrf(ExportResult& r, const CompensatorSettings& s) {
  LineEditor ed(r.original);
  const std::string drive = std::to_string(s.rrf_drive);
  const RrfLines lines = find_rrf_lines(ed, drive);
  std::vector<std::string> new_lines;
  check_config_override(r, s, lines, drive);
  if (s.pa_k_s) write_rrf_advance(r, ed, s, lines, drive, new_lines);
  if (s.pa_smooth_s)
    r.warnings.push_back(
        "RepRapFirmware has no pressure-advance smoothing time: the extruder's M201 E acceleration "
        "limit applies instead; smoothing time not written");

  std::string axis;
  const ShaperSetting* sh = rrf_single_shaper(s, r.warnings, &axis);
  if (sh) write_rrf_shaper(r, ed, *sh, lines, new_lines);

  if (!new_lines.empty()) {
    std::size_t at = ed.size();
    if (lines.m572 && !lines.m593 && sh) at = *lines.m572 + 1;
    else if (lines.anchor) at = *lines.anchor + 1;
    else if (lines.m501) at = *lines.m501;
    ed.insert_before(at, new_lines);
    for (auto& c : r.changes)
      if (c.where == "new line") c.line = at;
  }

  if (s.thermal) write_rrf_thermal(r, ed, s);
  r.updated = ed.render();
  r.diff = ed.unified_diff(r.path);
  std::string g;
  if (s.thermal) {
    const RrfM307Values v = rrf_m307_values(*s.thermal);
    g += fmt::format("M307 H{} R{} K{} D{} E{}\n", s.thermal->rrf_heater, v.r, v.k, v.d, v.e);
  }
  if (s.pa_k_s) g += fmt::format("M572 D{} S{}\n", drive, format_number(*s.pa_k_s, kDecimalsK));
  if (sh)
    g += fmt::format("M593 P\"{}\" F{} S{}\n", firmware_shaper_name(ExportFirmware::rrf, sh->type),
                     format_number(sh->freq_hz, kDecimalsFreq), format_number(sh->damping, kDecimalsZeta));
  r.gcode = g;
  if (r.updated != r.original)
    r.notes.push_back(
        "RepRapFirmware runs config.g at start-up: restart the board (M999) after writing, or send the "
        "G-code above to apply the values now");
}

}  // namespace tunekit::firmware::detail
