// Marlin Configuration_adv.h writer. Options are preprocessor lines, `#define NAME VALUE`,
// disabled by commenting them out (`//#define NAME`). Enabling a feature removes the `//`;
// setting a value rewrites only the value token (keeping a `{ }` list form, an `f` suffix and
// the column of a trailing comment). Also emits the equivalent G-code (M900, M593, M500).
#include <algorithm>
#include <cctype>
#include <optional>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/config_edit.hpp"
#include "text_util.hpp"

namespace tunekit::protocols::detail {
namespace {

struct Define {
  std::size_t line = 0;
  bool commented = false;
  std::size_t indent_end = 0;   // where "//" (or "#define") starts
  std::size_t define_at = 0;    // where "#define" starts
  std::size_t value_begin = 0;  // value token (empty for a flag)
  std::size_t value_end = 0;
  std::string value;
};

std::optional<Define> parse_define(const std::string& t, const std::string& name, std::size_t line) {
  Define d;
  d.line = line;
  std::size_t p = 0;
  while (p < t.size() && text::is_blank(t[p])) ++p;
  d.indent_end = p;
  if (t.compare(p, 2, "//") == 0) {
    d.commented = true;
    p += 2;
    while (p < t.size() && text::is_blank(t[p])) ++p;
  }
  if (t.compare(p, 7, "#define") != 0) return std::nullopt;
  d.define_at = p;
  p += 7;
  if (p >= t.size() || !text::is_blank(t[p])) return std::nullopt;
  while (p < t.size() && text::is_blank(t[p])) ++p;
  if (t.compare(p, name.size(), name) != 0) return std::nullopt;
  p += name.size();
  if (p < t.size() && !text::is_blank(t[p])) return std::nullopt;  // a longer name (ADVANCE_K_EXTRA)
  std::size_t vb = p;
  while (vb < t.size() && text::is_blank(t[vb])) ++vb;
  if (vb >= t.size() || t.compare(vb, 2, "//") == 0 || t.compare(vb, 2, "/*") == 0) {
    d.value_begin = d.value_end = p;
    return d;
  }
  std::size_t ve = vb;
  if (t[vb] == '{') {
    ve = t.find('}', vb);
    ve = ve == std::string::npos ? t.size() : ve + 1;
  } else {
    while (ve < t.size() && !text::is_blank(t[ve])) ++ve;
  }
  d.value_begin = vb;
  d.value_end = ve;
  d.value = t.substr(vb, ve - vb);
  return d;
}

std::vector<Define> find_defines(const LineEditor& ed, const std::string& name) {
  std::vector<Define> out;
  for (std::size_t i = 0; i < ed.size(); ++i)
    if (auto d = parse_define(ed.line(i), name, i)) out.push_back(*d);
  return out;
}

std::string uncomment(const std::string& t, const Define& d) { return t.substr(0, d.indent_end) + t.substr(d.define_at); }

/// The number inside a value token ("0.15f" -> "0.15", "{ 0.22 }" -> "0.22").
std::string bare_number(std::string v) {
  if (!v.empty() && v.front() == '{') {
    v = v.substr(1, v.size() >= 2 ? v.size() - 2 : 0);
    const auto b = v.find_first_not_of(" \t");
    const auto e = v.find_last_not_of(" \t");
    v = b == std::string::npos ? std::string() : v.substr(b, e - b + 1);
  }
  if (!v.empty() && (v.back() == 'f' || v.back() == 'F')) v.pop_back();
  return v;
}

class MarlinEditor {
 public:
  explicit MarlinEditor(ExportResult& r) : r_(r), ed_(r.original) {}

  /// Enables a feature flag; false when the file has no such line.
  bool enable(const std::string& name) {
    const auto defs = find_defines(ed_, name);
    if (defs.empty()) return false;
    for (const auto& d : defs)
      if (!d.commented) return true;
    const auto& d = defs.front();
    ed_.replace(d.line, uncomment(ed_.line(d.line), d));
    r_.changes.push_back({name, "disabled", "enabled", d.line + 1, "feature flag"});
    return true;
  }

  /// Sets a value define; false when the file has no such line.
  bool set(const std::string& name, double v, int decimals) {
    const auto defs = find_defines(ed_, name);
    if (defs.empty()) return false;
    const bool any_active = std::any_of(defs.begin(), defs.end(), [](const Define& d) { return !d.commented; });
    for (const auto& d0 : defs) {
      if (d0.commented && any_active) continue;
      std::string t = ed_.line(d0.line);
      Define d = d0;
      if (d.commented) {
        t = uncomment(t, d);
        d = *parse_define(t, name, d.line);
      }
      const std::string old_num = bare_number(d.value);
      if (!d0.commented && !d.value.empty() && same_number(old_num, v, decimals)) continue;
      std::string nv = format_number(v, decimals);
      if (!d.value.empty() && (d.value.back() == 'f' || d.value.back() == 'F') && d.value.front() != '{') nv += 'f';
      if (!d.value.empty() && d.value.front() == '{') nv = "{ " + nv + " }";
      std::string rest = t.substr(d.value_end);
      if (d.value.empty()) {
        // A define without a value: add one after the name.
        t = t.substr(0, d.value_begin) + " " + nv + rest;
      } else {
        const std::size_t spaces = rest.find_first_not_of(" \t");
        if (spaces != std::string::npos && spaces > 0) {
          const std::ptrdiff_t width = static_cast<std::ptrdiff_t>(spaces) + static_cast<std::ptrdiff_t>(d.value.size()) -
                                       static_cast<std::ptrdiff_t>(nv.size());
          rest = std::string(static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, width)), ' ') + rest.substr(spaces);
        }
        t = t.substr(0, d.value_begin) + nv + rest;
      }
      if (t == ed_.line(d0.line)) continue;
      ed_.replace(d0.line, t);
      r_.changes.push_back({name, d0.commented ? "(commented out) " + d0.value : d0.value, nv, d0.line + 1, "define"});
    }
    return true;
  }

  LineEditor& editor() { return ed_; }

 private:
  ExportResult& r_;
  LineEditor ed_;
};

}  // namespace

void write_marlin(ExportResult& r, const CompensatorSettings& s) {
  MarlinEditor m(r);
  bool tau_written = false;
  if (s.pa_k_s || s.pa_smooth_s) {
    if (!m.enable("LIN_ADVANCE"))
      r.warnings.push_back(fmt::format("{}: no LIN_ADVANCE line; in Marlin bugfix-2.1.x it lives in Configuration.h: "
                                       "enable it there",
                                       r.path));
  }
  if (s.pa_k_s && !m.set("ADVANCE_K", *s.pa_k_s, kDecimalsK))
    throw InputError("no '#define ADVANCE_K' line: this does not look like a Marlin 2.x Configuration_adv.h", r.path);
  if (s.pa_smooth_s) {
    if (!m.enable("SMOOTH_LIN_ADVANCE")) {
      r.warnings.push_back(fmt::format("{}: no SMOOTH_LIN_ADVANCE line (Marlin before 2.1.3 has none): ADVANCE_TAU "
                                       "not written and U left out of M900",
                                       r.path));
    } else if (!m.set("ADVANCE_TAU", *s.pa_smooth_s, kDecimalsSmooth)) {
      r.warnings.push_back(fmt::format("{}: SMOOTH_LIN_ADVANCE is present but no '#define ADVANCE_TAU' line: "
                                       "ADVANCE_TAU not written",
                                       r.path));
    } else {
      tau_written = true;
    }
  }
  for (const auto& [axis, sh] : s.shapers) {
    std::string A = axis;
    std::transform(A.begin(), A.end(), A.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    if (!m.enable("INPUT_SHAPING_" + A))
      throw InputError(fmt::format("no 'INPUT_SHAPING_{}' line: Marlin 2.1.2 or later is needed for input shaping", A),
                       r.path);
    if (!m.set("SHAPING_FREQ_" + A, sh.freq_hz, kDecimalsFreq))
      throw InputError(fmt::format("no '#define SHAPING_FREQ_{}' line", A), r.path);
    if (!m.set("SHAPING_ZETA_" + A, sh.damping, kDecimalsZeta))
      throw InputError(fmt::format("no '#define SHAPING_ZETA_{}' line", A), r.path);
  }
  r.updated = m.editor().render();
  r.diff = m.editor().unified_diff(r.path);

  std::string g;
  if (s.pa_k_s || (s.pa_smooth_s && tau_written)) {
    g += "M900";
    if (s.pa_k_s) g += " K" + format_number(*s.pa_k_s, kDecimalsK);
    if (s.pa_smooth_s && tau_written) g += " U" + format_number(*s.pa_smooth_s, kDecimalsSmooth);
    g += "\n";
  }
  for (const auto& [axis, sh] : s.shapers) {
    std::string A = axis;
    std::transform(A.begin(), A.end(), A.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    g += fmt::format("M593 {} F{} D{}\n", A, format_number(sh.freq_hz, kDecimalsFreq),
                     format_number(sh.damping, kDecimalsZeta));
  }
  if (!g.empty()) g += "M500\n";
  r.gcode = g;
}

}  // namespace tunekit::protocols::detail
