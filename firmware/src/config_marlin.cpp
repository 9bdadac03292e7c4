// Marlin Configuration_adv.h writer. Options are preprocessor lines, `#define NAME VALUE`,
// disabled by commenting them out (`//#define NAME`). Enabling a feature removes the `//`;
// setting a value rewrites only the value token (keeping a `{ }` list form, an `f` suffix and
// the column of a trailing comment). Also emits the equivalent G-code (M900, M593, M500).
#include <algorithm>
#include <cstdlib>
#include <cctype>
#include <iterator>
#include <optional>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "text_util.hpp"

namespace tunekit::firmware::detail {
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

std::string uncomment(const std::string& t, const Define& d) {
  return t.substr(0, d.indent_end) + t.substr(d.define_at);
}

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

/// Whether `name` is defined (not commented out) in the text.
bool is_enabled(const LineEditor& ed, const std::string& name) {
  for (const auto& d : find_defines(ed, name))
    if (!d.commented) return true;
  return false;
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

  /// Comments out every active definition of a flag (Marlin's "//#define NAME").
  void disable(const std::string& name) {
    for (const auto& d : find_defines(ed_, name)) {
      if (d.commented) continue;
      const std::string& t = ed_.line(d.line);
      ed_.replace(d.line, t.substr(0, d.indent_end) + "//" + t.substr(d.define_at));
      r_.changes.push_back({name, "enabled", "disabled", d.line + 1, "feature flag"});
    }
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
      // A per-extruder list "{ 0.22, 0.30 }" (DISTINCT_E_FACTORS) keeps its other entries: only
      // entry `index_` is set.
      if (!d.value.empty() && d.value.front() == '{' && d.value.find(',') != std::string::npos) {
        std::vector<std::string> items;
        std::string inner = d.value.substr(1, d.value.size() >= 2 ? d.value.size() - 2 : 0);
        std::size_t b = 0;
        for (;;) {
          const auto e = inner.find(',', b);
          std::string it = inner.substr(b, e == std::string::npos ? std::string::npos : e - b);
          const auto f = it.find_first_not_of(" \t"), l = it.find_last_not_of(" \t");
          items.push_back(f == std::string::npos ? std::string() : it.substr(f, l - f + 1));
          if (e == std::string::npos) break;
          b = e + 1;
        }
        if (index_ >= items.size())
          throw InputError(fmt::format("{}:{}: {} has {} entries (one per extruder); extruder {} has none", r_.path,
                                       d0.line + 1, name, items.size(), index_));
        if (!d0.commented && same_number(bare_number(items[index_]), v, decimals)) continue;
        std::string item = format_number(v, decimals);
        if (!items[index_].empty() && (items[index_].back() == 'f' || items[index_].back() == 'F'))
          item += item.find('.') == std::string::npos ? ".0f" : "f";
        items[index_] = item;
        std::string nv = "{ ";
        for (std::size_t k = 0; k < items.size(); ++k) nv += (k ? ", " : "") + items[k];
        nv += " }";
        t = t.substr(0, d.value_begin) + nv + t.substr(d.value_end);
        if (t == ed_.line(d0.line)) continue;
        ed_.replace(d0.line, t);
        r_.changes.push_back({name, d0.value, nv, d0.line + 1, fmt::format("define (extruder {})", index_)});
        continue;
      }
      if (index_ > 0 && !d.value.empty())
        r_.warnings.push_back(
            fmt::format("{}:{}: {} holds one value for every extruder; it is set for all, not only "
                        "extruder {}",
                        r_.path, d0.line + 1, name, index_));
      const std::string old_num = bare_number(d.value);
      if (!d0.commented && !d.value.empty() && same_number(old_num, v, decimals)) continue;
      std::string nv = format_number(v, decimals);
      if (!d.value.empty() && (d.value.back() == 'f' || d.value.back() == 'F') && d.value.front() != '{') {
        if (nv.find('.') == std::string::npos) nv += ".0";  // "45f" is not a C float literal
        nv += 'f';
      }
      if (!d.value.empty() && d.value.front() == '{') {
        // "{ 40.0f }" (Configuration.h's per-hotend MPC lists) keeps its float suffix.
        const std::string inner = d.value.substr(0, d.value.find('}'));
        if (inner.find_last_not_of(" \t") != std::string::npos &&
            (inner[inner.find_last_not_of(" \t")] == 'f' || inner[inner.find_last_not_of(" \t")] == 'F'))
          nv += nv.find('.') == std::string::npos ? ".0f" : "f";
        nv = "{ " + nv + " }";
      }
      std::string rest = t.substr(d.value_end);
      if (d.value.empty()) {
        // A define without a value: add one after the name.
        t = t.substr(0, d.value_begin) + " " + nv + rest;
      } else {
        const std::size_t spaces = rest.find_first_not_of(" \t");
        if (spaces != std::string::npos && spaces > 0) {
          const std::ptrdiff_t width = static_cast<std::ptrdiff_t>(spaces) +
                                       static_cast<std::ptrdiff_t>(d.value.size()) -
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
  /// The extruder whose entry a per-extruder list gets.
  void set_index(std::size_t i) { index_ = i; }

 private:
  std::size_t index_ = 0;
  ExportResult& r_;
  LineEditor ed_;
};

}  // namespace

namespace {

/// The runtime M493 lines for a Marlin running fixed-time motion, in the letters of the form its
/// M493 report took (marlin_m493.hpp, Marlin/src/gcode/feature/ft_motion/M493.cpp): S1 keeps
/// fixed-time motion on, the shapers by ftMotionShaper_t code (ft_types.h order), damping at
/// least 0.01 (M493 accepts 0.01-1), then the advance gain where the form has a letter for it.
/// What the form cannot say becomes a warning.
std::string marlin_m493_gcode(ExportResult& r, const CompensatorSettings& s) {
  std::vector<FtShaperWords> axes;
  for (const auto& [axis, sh] : s.shapers) {
    const std::string t = firmware_shaper_name(ExportFirmware::marlin, sh.type, true);
    int code = 0;
    for (std::size_t i = 0; i < std::size(limits::kMarlinFtMotionShapers); ++i)
      if (t == limits::kMarlinFtMotionShapers[i].firmware_name) code = static_cast<int>(i) + 1;
    axes.push_back({axis, code, format_number(sh.freq_hz, kDecimalsFreq),
                    format_number(std::max(0.01, sh.damping), kDecimalsZeta)});
  }
  auto set = m493_set_shapers(s.marlin_m493, axes, true);
  std::string g;
  for (const auto& l : set.lines) g += l + "\n";
  if (s.pa_k_s) {
    const std::string la = m493_linear_advance(s.marlin_m493, format_number(*s.pa_k_s, kDecimalsK));
    if (la.empty())
      set.left_out.push_back(fmt::format("the advance K {} (this form's M493 has no linear advance letter)",
                                         format_number(*s.pa_k_s, kDecimalsK)));
    else g += la + "\n";
  }
  if (s.marlin_m493.form == M493Form::none && !g.empty())
    r.warnings.push_back(
        fmt::format("{}: the printer's M493 report did not show which letters its M493 takes (no "
                    "axis was shaped): the G-code uses those of 2024-2025 (axis_named); check them "
                    "against the build's M493",
                    r.path));
  for (const auto& what : set.left_out)
    r.warnings.push_back(fmt::format("{}: the printer's M493 ({} form) cannot set {}: it is left out of the G-code",
                                     r.path, to_string(s.marlin_m493), what));
  return g;
}

/// FT_MOTION build (Marlin/src/module/ft_motion.cpp): with fixed-time motion active (M493 S1)
/// the classic shaper and smooth linear advance are bypassed (stepper.cpp isr()), so the
/// FT_MOTION defaults are written instead: FTM_DEFAULT_SHAPER_X/Y (ftMotionShaper_<TYPE>,
/// ft_types.h), FTM_SHAPING_DEFAULT_FREQ_X/Y, FTM_SHAPING_ZETA_X/Y; advance K goes to ADVANCE_K
/// (FTM_LINEAR_ADV_DEFAULT_K on builds that have it).
void write_marlin_ft_motion(ExportResult& r, const CompensatorSettings& s, MarlinEditor& m) {
  auto replace_token = [&](const std::string& name, const std::string& value) {
    const auto defs = find_defines(m.editor(), name);
    for (const auto& d : defs) {
      if (d.commented || d.value.empty() || d.value == value) continue;
      const std::string& t = m.editor().line(d.line);
      m.editor().replace(d.line, t.substr(0, d.value_begin) + value + t.substr(d.value_end));
      r.changes.push_back({name, d.value, value, d.line + 1, "define (FT_MOTION)"});
      return true;
    }
    return std::any_of(defs.begin(), defs.end(), [](const Define& d) { return !d.commented; });
  };
  // A printer that runs fixed-time motion with a file that does not build it: the file is not
  // the running build's, and its classic lines would be bypassed; only the M493 G-code applies.
  const bool file_has_ft = marlin_ft_motion_enabled(r.original);
  if (s.marlin_ft_motion_live && !file_has_ft) {
    r.warnings.push_back(
        fmt::format("{}: the printer runs fixed-time motion (M493 reports it enabled) but this file "
                    "does not enable FT_MOTION: it is not the running build's configuration; its "
                    "classic shaper and advance lines are left alone (FT_MOTION bypasses them) and the "
                    "settings are in the M493 G-code",
                    r.path));
  } else {
    m.set_index(static_cast<std::size_t>(s.extruder_index));
    if (s.pa_k_s) {
      const bool ftm_k = !find_defines(m.editor(), "FTM_LINEAR_ADV_DEFAULT_K").empty();
      if (!m.set(ftm_k ? "FTM_LINEAR_ADV_DEFAULT_K" : "ADVANCE_K", *s.pa_k_s, kDecimalsK))
        throw InputError("FT_MOTION build without an ADVANCE_K or FTM_LINEAR_ADV_DEFAULT_K line", r.path);
    }
    for (const auto& [axis, sh] : s.shapers) {
      const std::string A = axis == "x" ? "X" : "Y";
      const std::string type = firmware_shaper_name(ExportFirmware::marlin, sh.type, true);
      if (!replace_token("FTM_DEFAULT_SHAPER_" + A, "ftMotionShaper_" + type))
        throw InputError(fmt::format("FT_MOTION is enabled but there is no '#define FTM_DEFAULT_SHAPER_{}' line", A),
                         r.path);
      if (!m.set("FTM_SHAPING_DEFAULT_FREQ_" + A, sh.freq_hz, kDecimalsFreq))
        throw InputError(fmt::format("no '#define FTM_SHAPING_DEFAULT_FREQ_{}' line", A), r.path);
      if (!m.set("FTM_SHAPING_ZETA_" + A, sh.damping, kDecimalsZeta))
        throw InputError(fmt::format("no '#define FTM_SHAPING_ZETA_{}' line", A), r.path);
    }
  }
  if (s.pa_smooth_s)
    r.warnings.push_back(
        fmt::format("{}: FT_MOTION is enabled: it bypasses SMOOTH_LIN_ADVANCE (stepper.cpp isr()), so "
                    "ADVANCE_TAU is not written",
                    r.path));
  r.updated = m.editor().render();
  r.diff = m.editor().unified_diff(r.path);
  std::string g;
  if (s.marlin_ft_motion_live) {
    g += marlin_m493_gcode(r, s);
  } else {
    // Known from the file only: M493's parameter letters differ between Marlin versions, so no
    // runtime shaping line is guessed; the compiled defaults are loaded with M502 and stored with M500.
    if (s.pa_k_s) g += fmt::format("M900 K{}\n", format_number(*s.pa_k_s, kDecimalsK));
    if (!s.shapers.empty())
      r.warnings.push_back(
          fmt::format("{}: FT_MOTION build: the shapers are written as FT_MOTION defaults; after "
                      "flashing send M502 then M500 (M493 sets them at run time, with version-specific "
                      "parameters)",
                      r.path));
  }
  if (!g.empty()) g += "M500\n";
  r.gcode = g;
  if (r.updated != r.original)
    r.notes.push_back(
        "Marlin uses the values stored in EEPROM (M500) over the compiled defaults in this file: after "
        "flashing the new build, send M502 (load the compiled values) then M500 (store them)");
}

// Linear advance: LIN_ADVANCE enabled, ADVANCE_K set, and ADVANCE_TAU with SMOOTH_LIN_ADVANCE
// where the build has them. True when ADVANCE_TAU was written.
bool write_marlin_advance(ExportResult& r, const CompensatorSettings& s, MarlinEditor& m) {
  bool tau_written = false;
  if (s.pa_k_s || s.pa_smooth_s) {
    if (!m.enable("LIN_ADVANCE"))
      r.warnings.push_back(
          fmt::format("{}: no LIN_ADVANCE line; in Marlin bugfix-2.1.x it lives in Configuration.h: "
                      "enable it there",
                      r.path));
  }
  m.set_index(static_cast<std::size_t>(s.extruder_index));
  if (s.pa_k_s && !m.set("ADVANCE_K", *s.pa_k_s, kDecimalsK))
    throw InputError("no '#define ADVANCE_K' line: this does not look like a Marlin 2.x Configuration_adv.h", r.path);
  if (s.pa_smooth_s) {
    if (!m.enable("SMOOTH_LIN_ADVANCE")) {
      r.warnings.push_back(
          fmt::format("{}: no SMOOTH_LIN_ADVANCE line (Marlin before 2.1.3 has none): ADVANCE_TAU "
                      "not written and U left out of M900",
                      r.path));
    } else if (!m.set("ADVANCE_TAU", *s.pa_smooth_s, kDecimalsSmooth)) {
      r.warnings.push_back(
          fmt::format("{}: SMOOTH_LIN_ADVANCE is present but no '#define ADVANCE_TAU' line: "
                      "ADVANCE_TAU not written",
                      r.path));
    } else {
      tau_written = true;
    }
  }
  return tau_written;
}

// SHAPING_MIN_FREQ sizes the shaping queue (stepper.h: shaping_echoes = max_step_rate /
// shaping_min_freq / 2 + 3); a lower frequency overflows it ("IS will also misbehave!",
// stepper.cpp). Without an explicit value it is the minimum of the compiled SHAPING_FREQ_X/Y.
void check_shaping_min_freq(ExportResult& r, const CompensatorSettings& s, MarlinEditor& m,
                            const LineEditor& original) {
  if (s.shapers.empty()) return;
  double min_new = 1e300;
  for (const auto& [axis, sh] : s.shapers) min_new = std::min(min_new, sh.freq_hz);
  const auto mins = find_defines(m.editor(), "SHAPING_MIN_FREQ");
  const Define* active = nullptr;
  for (const auto& d : mins)
    if (!d.commented) active = &d;
  if (active && !active->value.empty()) {
    const double v = std::strtod(bare_number(active->value).c_str(), nullptr);
    if (min_new < v)
      throw InputError(
          fmt::format("{}:{}: SHAPING_MIN_FREQ is {} Hz but the shaper frequency {} Hz is lower; Marlin "
                      "sizes its shaping queue for SHAPING_MIN_FREQ and misbehaves below it "
                      "(Marlin/src/module/stepper.h shaping_echoes); lower SHAPING_MIN_FREQ by hand "
                      "if the board's RAM allows it",
                      r.path, active->line + 1, bare_number(active->value), format_number(min_new, 2)));
    return;
  }
  double compiled = 1e300;
  for (const char* A : {"X", "Y"}) {
    if (!is_enabled(original, std::string("INPUT_SHAPING_") + A)) continue;
    for (const auto& d : find_defines(original, std::string("SHAPING_FREQ_") + A))
      if (!d.commented && !d.value.empty())
        compiled = std::min(compiled, std::strtod(bare_number(d.value).c_str(), nullptr));
  }
  if (compiled < 1e300 && compiled > 0 && min_new < compiled)
    r.warnings.push_back(fmt::format(
        "{}: without SHAPING_MIN_FREQ the running build's minimum shaping frequency is its lowest compiled "
        "SHAPING_FREQ ({} Hz): send the M593 lines only after flashing the new build, not to the running one "
        "(Marlin/src/module/stepper.h)",
        r.path, format_number(compiled, 2)));
}

// The axis letter in upper case.
std::string upper_axis(const std::string& axis) {
  std::string A = axis;
  std::transform(A.begin(), A.end(), A.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return A;
}

// The G-code that applies the values to the running printer: M900 and M593, then M500.
std::string marlin_runtime_gcode(ExportResult& r, const CompensatorSettings& s, const LineEditor& original,
                                 bool tau_written) {
  std::string g;
  // Marlin/src/gcode/feature/advance/M900.cpp: with ADVANCE_K_EXTRA and slot 1 active, "M900 K"
  // sets the backup slot; "S0" selects slot 0 first, so K becomes the active value. T picks the
  // extruder.
  const bool k_extra = is_enabled(original, "ADVANCE_K_EXTRA");
  if (s.pa_k_s || (s.pa_smooth_s && tau_written)) {
    g += "M900";
    if (s.extruder_index > 0) g += fmt::format(" T{}", s.extruder_index);
    if (k_extra && s.pa_k_s) g += " S0";
    if (s.pa_k_s) g += " K" + format_number(*s.pa_k_s, kDecimalsK);
    if (s.pa_smooth_s && tau_written) g += " U" + format_number(*s.pa_smooth_s, kDecimalsSmooth);
    g += "\n";
  }
  for (const auto& [axis, sh] : s.shapers) {
    const std::string A = upper_axis(axis);
    // M593.cpp: on a build without INPUT_SHAPING_X, "M593 X" is not seen as an axis and the
    // values go to every shaped axis (Y). When the running build shapes another axis but not
    // this one, its line is left out (the new build, flashed, has both).
    const bool other_shaped = is_enabled(original, A == "X" ? "INPUT_SHAPING_Y" : "INPUT_SHAPING_X");
    if (!is_enabled(original, "INPUT_SHAPING_" + A) && other_shaped) {
      r.warnings.push_back(
          fmt::format("{}: the running build has no INPUT_SHAPING_{}: its M593 line is left out (on "
                      "such a build 'M593 {}' would set the other axis); flash the new build",
                      r.path, A, A));
      continue;
    }
    g += fmt::format("M593 {} F{} D{}\n", A, format_number(sh.freq_hz, kDecimalsFreq),
                     format_number(sh.damping, kDecimalsZeta));
  }
  if (!g.empty()) g += "M500\n";
  return g;
}

// The hot end's model-predictive control (Marlin/Configuration.h, "Model Predictive Control for
// hotend"): MPCTEMP on, PIDTEMP off (SanityCheck.h refuses both), the model's defines set for the
// extruder's entry of their per-hotend lists.
void write_marlin_thermal(ExportResult& r, const CompensatorSettings& s, MarlinEditor& m) {
  if (!m.enable("MPCTEMP"))
    throw InputError(
        "no 'MPCTEMP' line: the thermal model is written into Marlin's Configuration.h (Marlin 2.1.2 or "
        "later), not Configuration_adv.h",
        r.path);
  m.disable("PIDTEMP");
  m.set_index(static_cast<std::size_t>(s.extruder_index));
  for (const auto& d : marlin_mpc_defines(*s.thermal)) {
    if (d.name == "MPC_AMBIENT_XFER_COEFF_FAN255") m.enable("MPC_INCLUDE_FAN");
    if (!m.set(d.name, d.value, d.decimals))
      throw InputError(fmt::format("no '#define {}' line in the MPC section", d.name), r.path);
  }
}

}  // namespace

void write_marlin(ExportResult& r, const CompensatorSettings& s) {
  const LineEditor original(r.original);
  MarlinEditor m(r);
  if (s.thermal) write_marlin_thermal(r, s, m);
  // Fixed-time motion bypasses the classic shaper and smooth linear advance: nothing of them is
  // touched (stepper.cpp isr()).
  if (s.marlin_ft_motion) {
    write_marlin_ft_motion(r, s, m);
    if (s.thermal) r.gcode = marlin_m306_gcode(*s.thermal, s.extruder_index) + (r.gcode.empty() ? "M500\n" : r.gcode);
    return;
  }
  const bool tau_written = write_marlin_advance(r, s, m);
  check_shaping_min_freq(r, s, m, original);
  for (const auto& [axis, sh] : s.shapers) {
    const std::string A = upper_axis(axis);
    m.set_index(0);
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
  r.gcode = marlin_runtime_gcode(r, s, original, tau_written);
  if (s.thermal) r.gcode = marlin_m306_gcode(*s.thermal, s.extruder_index) + (r.gcode.empty() ? "M500\n" : r.gcode);
  // Precedence: with EEPROM_SETTINGS, Marlin loads the stored values at boot over the compiled
  // defaults (Marlin/src/MarlinCore.cpp setup(): settings.first_load(), "Load data from EEPROM if
  // available (or use defaults)"; M502 resets to the compiled ones, M500 stores them).
  if (r.updated != r.original)
    r.notes.push_back(
        "Marlin uses the values stored in EEPROM (M500) over the compiled defaults in this file: after "
        "flashing the new build, send M502 (load the compiled values) then M500 (store them); or send "
        "the G-code above (it ends with M500) to the running printer");
}

}  // namespace tunekit::firmware::detail
