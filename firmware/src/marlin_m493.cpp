#include "tunekit/firmware/marlin_m493.hpp"

#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::firmware {
namespace {

/// A shaper's name in say_shaping() and the code M493 takes for it: ftMotionShaper_t
/// (Marlin/src/module/ft_types.h) and, in the mode form, ftMotionMode_t (0 when the mode form
/// has no such shaper: ZVDD and ZVDDD came with per-axis shaping).
struct ShaperName {
  const char* name;
  int code;
  int mode_code;
};
constexpr ShaperName kShapers[] = {{"None", 0, 0},       {"ZV", 1, 10},        {"ZVD", 2, 11},
                                   {"ZVDD", 3, 0},       {"ZVDDD", 4, 0},      {"EI", 5, 12},
                                   {"2 Hump EI", 6, 13}, {"3 Hump EI", 7, 14}, {"MZV", 8, 15}};

/// The axis a report names by its stepper ("X/A" in 2024's form; "A"/"B"/"C" on core builds).
std::string axis_of(const std::string& token) {
  if (token == "X" || token == "A" || token == "X/A") return "x";
  if (token == "Y" || token == "B" || token == "Y/B") return "y";
  if (token == "Z" || token == "C" || token == "Z/C") return "z";
  if (token == "E") return "e";
  return {};
}

void add_axis(FtMotionReport& r, const std::string& axis, const std::string& name, bool mode_form) {
  if (axis.empty()) return;
  FtAxisShaper s;
  s.name = name;
  for (const auto& k : kShapers)
    if (name == k.name) s.code = mode_form ? k.mode_code : k.code;
  r.axes[axis] = s;
  if (s.code != 0) r.shapers[axis] = name;
}

/// "(X=ZV ; Y=None)": the axis_list form.
void read_list(FtMotionReport& r, const std::string& inner) {
  std::size_t b = 0;
  while (b < inner.size()) {
    auto e = inner.find(" ; ", b);
    if (e == std::string::npos) e = inner.size();
    const std::string item = inner.substr(b, e - b);
    const auto eq = item.find('=');
    if (eq != std::string::npos) add_axis(r, axis_of(item.substr(0, eq)), item.substr(eq + 1), false);
    b = e + 3;
  }
}

/// " with X axis ZV shaping and with Y axis MZV shaping" (axis_named/axis_slash) or
/// " with ZV shaping" (mode, both axes).
void read_with(FtMotionReport& r, const std::string& rest) {
  for (std::size_t p = rest.find(" with "); p != std::string::npos; p = rest.find(" with ", p + 1)) {
    const auto b = p + 6;
    const auto end = rest.find(" shaping", b);
    if (end == std::string::npos) return;
    const auto ax = rest.find(" axis ", b);
    if (ax == std::string::npos || ax > end) {
      r.form = M493Form::mode;
      add_axis(r, "x", rest.substr(b, end - b), true);
      add_axis(r, "y", rest.substr(b, end - b), true);
      return;
    }
    const std::string token = rest.substr(b, ax - b);
    r.form = token.find('/') != std::string::npos ? M493Form::axis_slash : M493Form::axis_named;
    add_axis(r, axis_of(token), rest.substr(ax + 6, end - ax - 6), false);
  }
}

/// The first report line: "Fixed-Time Motion enabled|disabled" and what follows it.
void read_state(FtMotionReport& r, const std::string& line, std::size_t at) {
  r.present = true;
  r.active = line.compare(at + 18, 7, "enabled") == 0;
  const auto abled = line.find("abled", at + 18);
  const std::string rest = abled == std::string::npos ? std::string() : line.substr(abled + 5);
  if (rest.rfind(" (", 0) == 0 && rest.find(')') != std::string::npos) {
    r.form = M493Form::axis_list;
    read_list(r, rest.substr(2, rest.find(')') - 2));
  } else {
    read_with(r, rest);
  }
}

/// "X/A static compensator frequency: 40.00Hz", "Y static shaper frequency: 37.00 Hz",
/// "Z shaper frequency: 21.00 Hz" (dynamic builds say "base dynamic" for "static").
void read_frequency(FtMotionReport& r, const std::string& line) {
  const auto f = line.find(" frequency: ");
  if (f == std::string::npos) return;
  if (line.find("compensator frequency") == std::string::npos && line.find("shaper frequency") == std::string::npos)
    return;
  const auto it = r.axes.find(axis_of(line.substr(0, line.find(' '))));
  if (it != r.axes.end()) it->second.freq_hz = std::strtod(line.c_str() + f + 12, nullptr);
}

void read_line(FtMotionReport& r, const std::string& line) {
  if (const auto ft = line.find("Fixed-Time Motion "); ft != std::string::npos) return read_state(r, line, ft);
  if (line.rfind("FTM V", 0) == 0) {
    r.version = std::atoi(line.c_str() + 5);
    return;
  }
  if (!r.present) return;
  if (const auto la = line.find("Linear Advance "); la != std::string::npos) {
    r.linear_advance = line.compare(la + 15, 7, "enabled") == 0;
    const auto g = line.find("Gain: ");
    if (g != std::string::npos) r.linear_advance_k = std::strtod(line.c_str() + g + 6, nullptr);
    return;
  }
  read_frequency(r, line);
}

char letter(const std::string& axis) { return static_cast<char>(axis[0] - 'a' + 'A'); }

/// ftMotionShaper_t's entry of a shaper code or report name (kShapers[0], None, when unknown).
const ShaperName& shaper_of(int code) {
  for (const auto& k : kShapers)
    if (k.code == code) return k;
  return kShapers[0];
}
int code_of(const std::string& name) {
  for (const auto& k : kShapers)
    if (name == k.name) return k.code;
  return 0;
}

/// " <letter><value>", or nothing for an empty value or no letter.
std::string word(char l, const std::string& value) {
  return l == '\0' || value.empty() ? std::string() : fmt::format(" {}{}", l, value);
}

/// The per-axis letters of the X/Y<shaper> forms: frequency A/B and damping I/J for X/Y (Z and E
/// have a shaper letter only).
char freq_letter(const std::string& axis) { return axis == "x" ? 'A' : axis == "y" ? 'B' : '\0'; }
char zeta_letter(const std::string& axis) { return axis == "x" ? 'I' : axis == "y" ? 'J' : '\0'; }

/// 2023: one S<mode> for X and Y, A/B frequency, no damping letter.
M493Lines mode_lines(const std::vector<FtShaperWords>& axes) {
  M493Lines out;
  const auto& first = axes.front();
  const ShaperName& sh = shaper_of(first.code);
  if (sh.mode_code == 0) {
    out.left_out.push_back(fmt::format("the {} shaper (the 2023 form's single mode has no such shaper)", sh.name));
    return out;
  }
  std::string line = fmt::format("M493 S{}", sh.mode_code);
  for (const auto& a : axes) {
    line += word(freq_letter(a.axis), a.freq_hz);
    if (a.code != first.code)
      out.left_out.push_back(
          fmt::format("the {} axis's own shaper type ({}): the 2023 form sets one mode for X and "
                      "Y, the {} axis's {}",
                      letter(a.axis), shaper_of(a.code).name, letter(first.axis), sh.name));
    if (!a.zeta.empty())
      out.left_out.push_back(
          fmt::format("the {} axis's damping ratio {} (the 2023 form has no damping letter)", letter(a.axis), a.zeta));
  }
  out.lines.push_back(line);
  return out;
}

/// FTM V2: one line per axis, the axis flagged, C<shaper> A<Hz> I<damping>.
M493Lines flag_lines(const std::vector<FtShaperWords>& axes, bool turn_on) {
  M493Lines out;
  for (const auto& a : axes)
    out.lines.push_back(
        fmt::format("M493{} {} C{}", turn_on && out.lines.empty() ? " S1" : "", letter(a.axis), a.code) +
        word('A', a.freq_hz) + word('I', a.zeta));
  return out;
}

/// 2024-2025: X/Y<shaper>, then A/B frequencies and I/J damping ratios, in one line.
M493Lines axis_lines(const std::vector<FtShaperWords>& axes, bool turn_on) {
  std::string line = turn_on ? "M493 S1" : "M493", freqs, zetas;
  for (const auto& a : axes) {
    line += fmt::format(" {}{}", letter(a.axis), a.code);
    freqs += word(freq_letter(a.axis), a.freq_hz);
    zetas += word(zeta_letter(a.axis), a.zeta);
  }
  return {{line + freqs + zetas}, {}};
}

}  // namespace

bool FtMotionReport::shaping() const { return active && !shapers.empty(); }

std::string to_string(M493Form f) {
  switch (f) {
    case M493Form::mode: return "mode";
    case M493Form::axis_slash: return "axis_slash";
    case M493Form::axis_named: return "axis_named";
    case M493Form::axis_list: return "axis_list";
    default: return "none";
  }
}

FtMotionReport parse_m493_report(const std::vector<std::string>& lines) {
  FtMotionReport r;
  for (const auto& raw : lines) read_line(r, raw.rfind("echo:", 0) == 0 ? raw.substr(5) : raw);
  return r;
}

std::vector<std::string> m493_shaping_off(const FtMotionReport& r) {
  if (!r.shaping()) return {};
  if (r.form == M493Form::mode) return {"M493 S1"};  // fixed-time motion, no shaping
  std::string line = "M493";
  for (const auto& [axis, name] : r.shapers)
    line += r.form == M493Form::axis_list && r.version >= 2 ? fmt::format(" {}", letter(axis))
                                                            : fmt::format(" {}0", letter(axis));
  if (r.form == M493Form::axis_list && r.version >= 2) line += " C0";
  return {line};
}

std::vector<std::string> m493_shaping_restore(const FtMotionReport& r) {
  if (!r.shaping()) return {};
  std::vector<FtShaperWords> axes;
  for (const auto& [axis, s] : r.axes) {
    if (!r.shapers.count(axis)) continue;
    const std::string f = std::isfinite(s.freq_hz) ? fmt::format("{:g}", s.freq_hz) : std::string();
    axes.push_back({axis, code_of(s.name), f, {}});
  }
  return m493_set_shapers(m493_syntax(r), axes, false).lines;
}

M493Syntax m493_syntax(const FtMotionReport& r) { return {r.form, r.form == M493Form::axis_list ? r.version : 1}; }

std::string to_string(const M493Syntax& s) {
  return s.form == M493Form::axis_list && s.version >= 2 ? "axis_list_v2" : to_string(s.form);
}

M493Syntax parse_m493_syntax(const std::string& name) {
  for (const M493Form f :
       {M493Form::none, M493Form::mode, M493Form::axis_slash, M493Form::axis_named, M493Form::axis_list})
    if (name == to_string(f)) return {f, 1};
  if (name == "axis_list_v2") return {M493Form::axis_list, 2};
  throw InputError(
      fmt::format("M493 form '{}' is not one of mode, axis_slash, axis_named, axis_list, axis_list_v2", name));
}

M493Lines m493_set_shapers(const M493Syntax& syntax, const std::vector<FtShaperWords>& axes, bool turn_on) {
  if (axes.empty()) return {};
  if (syntax.form == M493Form::mode) return mode_lines(axes);
  if (syntax.form == M493Form::axis_list && syntax.version >= 2) return flag_lines(axes, turn_on);
  return axis_lines(axes, turn_on);
}

std::string m493_linear_advance(const M493Syntax& syntax, const std::string& k) {
  if (syntax.form == M493Form::axis_list && syntax.version >= 2) return {};
  return "M493 P1 K" + k;
}

}  // namespace tunekit::firmware
