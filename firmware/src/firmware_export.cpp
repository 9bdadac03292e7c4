#include "tunekit/firmware/firmware_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "tunekit/core/file_lock.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/design/marlin_smoothing.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "text_util.hpp"

namespace tunekit::firmware {
namespace {

// Accepted ranges: firmware_limits.hpp gives each bound with its source.
constexpr double kMarlinKMax = limits::kMarlinAdvanceKMax;
constexpr double kMarlinTauMax = limits::kMarlinAdvanceTauMax_s;
constexpr double kKlipperSmoothMax = limits::kKlipperSmoothTimeMax_s;
constexpr double kRrfFreqMin = limits::kRrfShaperFreqMin_hz;
constexpr double kRrfFreqMax = limits::kRrfShaperFreqMax_hz;

/// `v` as the configuration will hold it: formatted with `decimals` and read back. A check of the
/// raw value would pass 1e-9 s that is written as 0, or a damping of 0.999999 written as 1.
double as_written(double v, int decimals) { return std::strtod(format_number(v, decimals).c_str(), nullptr); }

/// Every value of `s` as written; `rounded` tells whether formatting changed any of them.
CompensatorSettings written_values(const CompensatorSettings& s, bool& rounded) {
  CompensatorSettings w = s;
  const auto put = [&rounded](double& v, int decimals) {
    const double r = as_written(v, decimals);
    rounded = rounded || (r != v && std::isfinite(v));
    v = r;
  };
  if (w.pa_k_s) put(*w.pa_k_s, detail::kDecimalsK);
  if (w.pa_smooth_s) put(*w.pa_smooth_s, detail::kDecimalsSmooth);
  if (w.kalico) {
    put(w.kalico->linear_advance_s, detail::kDecimalsKalico);
    put(w.kalico->nonlinear_offset_mm, detail::kDecimalsKalico);
    put(w.kalico->linearization_velocity_mm_s, detail::kDecimalsKalico);
    if (w.kalico->time_offset_s) put(*w.kalico->time_offset_s, detail::kDecimalsKalico);
  }
  for (auto& [axis, sh] : w.shapers) {
    put(sh.freq_hz, detail::kDecimalsFreq);
    put(sh.damping, detail::kDecimalsZeta);
  }
  return w;
}

}  // namespace

bool marlin_ft_motion_enabled(const std::string& text) {
  const LineEditor ed(text);
  for (std::size_t i = 0; i < ed.size(); ++i) {
    const std::string& t = ed.line(i);
    std::size_t p = t.find_first_not_of(" \t");
    if (p == std::string::npos || t.compare(p, 7, "#define") != 0) continue;
    p = t.find_first_not_of(" \t", p + 7);
    if (p == std::string::npos || t.compare(p, 9, "FT_MOTION") != 0) continue;
    const std::size_t e = p + 9;
    if (e == t.size() || t[e] == ' ' || t[e] == '\t' || t[e] == '/') return true;
  }
  return false;
}

std::string z_shaper_refusal(ExportFirmware fw) {
  switch (fw) {
    case ExportFirmware::klipper: break;
    case ExportFirmware::kalico:
      return "a Z shaper is exported for Klipper only: Kalico's [input_shaper] reads the X and Y shapers only";
    case ExportFirmware::marlin:
      return "a Z shaper is exported for Klipper only: tunekit writes Marlin's X and Y shapers (INPUT_SHAPING_Z / "
             "M593 Z of Marlin 2.1.3 is not written)";
    case ExportFirmware::rrf:
      return "a Z shaper is exported for Klipper only: RepRapFirmware's M593 sets one shaper for every axis, "
             "the X/Y one tunekit writes";
  }
  return {};
}

ExportFirmware parse_export_firmware(const std::string& name) {
  const std::string n = core::lower(name);
  if (n == "klipper") return ExportFirmware::klipper;
  if (n == "kalico") return ExportFirmware::kalico;
  if (n == "marlin") return ExportFirmware::marlin;
  if (n == "rrf" || n == "reprapfirmware" || n == "duet") return ExportFirmware::rrf;
  throw InputError(fmt::format("unknown firmware '{}': use klipper, kalico, marlin or rrf", name));
}

std::string to_string(ExportFirmware fw) {
  switch (fw) {
    case ExportFirmware::klipper: return "klipper";
    case ExportFirmware::kalico: return "kalico";
    case ExportFirmware::marlin: return "marlin";
    case ExportFirmware::rrf: return "rrf";
  }
  return "?";
}

std::string canonical_shaper_type(const std::string& type) {
  const std::string t = core::lower(type);
  if (t == "ei2" || t == "2hei" || t == "2-hump-ei") return "2hump_ei";
  if (t == "ei3" || t == "3hei" || t == "3-hump-ei") return "3hump_ei";
  return t;
}

std::string firmware_shaper_name(ExportFirmware fw, const std::string& type, bool ft_motion) {
  const std::string t = canonical_shaper_type(type);
  if (const auto s = limits::find_shaper(fw, t, ft_motion)) return s->firmware_name;
  if (fw == ExportFirmware::marlin && ft_motion)
    throw InputError(
        fmt::format("Marlin's FT_MOTION has no '{}' input shaper (it has {})", type, limits::shaper_list(fw, true)));
  if (fw == ExportFirmware::rrf && t == "zvddd") return "zvddd";
  if (fw == ExportFirmware::marlin)
    throw InputError(fmt::format("Marlin's input shaping is ZV only; '{}' is not available (choose zv)", type));
  throw InputError(fmt::format("{} has no '{}' input shaper (it has {})", limits::firmware_title(fw), type,
                               limits::shaper_list(fw)));
}

void validate_settings(ExportFirmware fw, const CompensatorSettings& settings) {
  bool rounded = false;
  const CompensatorSettings s = written_values(settings, rounded);
  std::vector<std::string> bad;
  const std::string name = limits::firmware_title(fw);
  const bool klipper_like = fw == ExportFirmware::klipper || fw == ExportFirmware::kalico;
  if (s.kalico && fw != ExportFirmware::kalico)
    bad.push_back(fmt::format("the nonlinear advance model is Kalico's; {} does not read it", name));
  if (s.kalico && fw == ExportFirmware::kalico) detail::validate_kalico(*s.kalico, bad);
  if (s.thermal) validate_thermal(fw, *s.thermal, bad);
  if (s.pa_k_s) {
    const double k = *s.pa_k_s;
    if (!std::isfinite(k) || k < 0) bad.push_back(fmt::format("advance K {} s is negative or not a number", k));
    else if (fw == ExportFirmware::marlin && k > kMarlinKMax)
      bad.push_back(
          fmt::format("Marlin accepts K from 0 to {} (M900 K, Marlin/src/gcode/feature/advance/M900.cpp); {} is "
                      "out of range",
                      kMarlinKMax, k));
  }
  if (s.pa_smooth_s) {
    const double t = *s.pa_smooth_s;
    if (!std::isfinite(t) || t < 0) bad.push_back(fmt::format("smoothing time {} s is negative or not a number", t));
    else if (klipper_like && (t <= 0 || t > kKlipperSmoothMax))
      bad.push_back(
          fmt::format("Klipper accepts pressure_advance_smooth_time above 0 and up to {} s "
                      "(klippy/kinematics/extruder.py:15); {} is out of range",
                      kKlipperSmoothMax, t));
    else if (fw == ExportFirmware::marlin && (t <= 0 || t > kMarlinTauMax))
      // As for Klipper: a time written as 0 would silently turn the smoothing off.
      bad.push_back(
          fmt::format("Marlin's ADVANCE_TAU (M900 U) is written with {} decimals; {} s is out of range "
                      "(accepted: above 0, as written, up to {} s; 0 would turn the smoothing off)",
                      detail::kDecimalsSmooth, fmt::format("{:g}", *settings.pa_smooth_s), kMarlinTauMax));
  }
  for (const auto& [axis, sh] : s.shapers) {
    if (axis == "z" && fw != ExportFirmware::klipper) {
      bad.push_back(z_shaper_refusal(fw));
      continue;
    }
    if (axis != "x" && axis != "y" && axis != "z") {
      bad.push_back(fmt::format("input shaping on axis '{}' is not exported (x, y, and z for Klipper)", axis));
      continue;
    }
    try {
      firmware_shaper_name(fw, sh.type, s.marlin_ft_motion);
    } catch (const InputError& e) {
      bad.push_back(fmt::format("{}: {}", axis, e.message()));
    }
    // The firmware's own damping bound for this shaper (Klipper: per shaper).
    const auto fs = limits::find_shaper(fw, canonical_shaper_type(sh.type), s.marlin_ft_motion);
    if (fs && std::isfinite(sh.damping) && sh.damping >= 0 && sh.damping < 1 && sh.damping > fs->max_damping)
      bad.push_back(fmt::format("{}: {} accepts a damping ratio of at most {} for {} ({}); {} is out of range", axis,
                                name, fs->max_damping, fs->firmware_name, fs->source, sh.damping));
    if (!std::isfinite(sh.freq_hz) || sh.freq_hz <= 0)
      bad.push_back(fmt::format("{}: shaper frequency must be positive, not {} Hz", axis, sh.freq_hz));
    else if (fw == ExportFirmware::rrf && (sh.freq_hz < kRrfFreqMin || sh.freq_hz > kRrfFreqMax))
      bad.push_back(
          fmt::format("{}: RepRapFirmware accepts shaper frequencies from {:.2f} to {:.0f} Hz "
                      "(src/Movement/AxisShaper.cpp:81-82); {} is "
                      "out of range",
                      axis, kRrfFreqMin, kRrfFreqMax, sh.freq_hz));
    if (!std::isfinite(sh.damping) || sh.damping < 0 || sh.damping >= 1)
      bad.push_back(fmt::format("{}: damping ratio must be at least 0 and below 1, not {}", axis, sh.damping));
  }
  if (!bad.empty()) {
    std::string msg = fmt::format("refusing to write {} settings: ", name);
    for (std::size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
    if (rounded) msg += " (the values as written, rounded to the decimals of the configuration)";
    throw InputError(msg);
  }
}

ExportResult export_config_text(ExportFirmware fw, const std::string& text, const std::string& path,
                                const CompensatorSettings& settings) {
  CompensatorSettings s = settings;
  if (fw == ExportFirmware::marlin && (marlin_ft_motion_enabled(text) || s.marlin_ft_motion_live))
    s.marlin_ft_motion = true;
  validate_settings(fw, s);
  ExportResult r;
  r.firmware = fw;
  r.path = path;
  r.original = text;
  static const std::map<ExportFirmware, std::vector<std::string>> kCommentMarkers = {
      {ExportFirmware::klipper, {"#", ";"}},
      {ExportFirmware::kalico, {"#", ";"}},
      {ExportFirmware::marlin, {"//"}},
      {ExportFirmware::rrf, {";"}}};
  const ScopedCommentNote note(kCommentMarkers.at(fw), s.change_note);
  switch (fw) {
    case ExportFirmware::klipper:
    case ExportFirmware::kalico: detail::write_klipper(r, s); break;
    case ExportFirmware::marlin: detail::write_marlin(r, s); break;
    case ExportFirmware::rrf: detail::write_rrf(r, s); break;
  }
  return r;
}

ExportResult export_config_file(ExportFirmware fw, const std::string& path, const CompensatorSettings& s) {
  return export_config_text(fw, read_config_file(path), path, s);
}

std::string apply_export(const ExportResult& r, const std::function<void(const std::string&)>& before_rename) {
  if (!r.changed()) return {};
  // Writers of one configuration take turns (file_lock.hpp): compare and replace under the lock.
  const core::FileLock lock(r.path);
  lock.remove_stale_temporaries();
  // Refuse to overwrite a file that changed since it was read.
  if (read_config_file(r.path) != r.original)
    throw InputError("the configuration file changed since it was read; run the export again", r.path);
  return write_with_backup(r.path, r.updated, before_rename);
}

nlohmann::json ExportResult::to_json() const {
  nlohmann::json ch = nlohmann::json::array();
  for (const auto& c : changes)
    ch.push_back({{"key", c.key}, {"old", c.old_value}, {"new", c.new_value}, {"line", c.line}, {"where", c.where}});
  return {{"firmware", to_string(firmware)},
          {"config", path},
          {"changed", changed()},
          {"changes", ch},
          {"warnings", warnings},
          {"notes", notes},
          {"diff", diff},
          {"gcode", gcode}};
}

std::optional<double> smoothing_time_for(ExportFirmware fw, const design::AdvanceDesign& d) {
  double w = design::kAdvanceNaN;
  // Kalico's smoother is a 4th-order polynomial kernel whose peak (15/8) is below the
  // triangle's 2: the triangular window is the safe choice for both.
  if (fw == ExportFirmware::klipper || fw == ExportFirmware::kalico) w = d.window_triangular_s;
  if (fw == ExportFirmware::marlin) {
    // Marlin smooths with its own exponential cascade, designed on the written grid.
    if (!std::isfinite(d.window_box_s) || d.window_box_s <= 0) return std::nullopt;
    const double tau =
        design::design_marlin_advance_tau(d.window_box_s, {}, std::pow(10.0, -detail::kDecimalsSmooth)).tau_s;
    // A time that would be written as 0 turns the smoothing off: none is designed then.
    if (!(std::round(tau * std::pow(10.0, detail::kDecimalsSmooth)) > 0)) return std::nullopt;
    return tau;
  }
  if (!std::isfinite(w) || w <= 0) return std::nullopt;
  const double scale = std::pow(10.0, detail::kDecimalsSmooth);
  // The design is the shortest window the extruder's acceleration allows; Klipper's default is
  // kept unless that minimum is longer.
  return std::max(limits::kKlipperSmoothTimeDefault_s, std::max(1.0 / scale, std::ceil(w * scale - 1e-9) / scale));
}

std::string advance_schedule_gcode(ExportFirmware fw, const std::vector<design::ScheduledAdvance>& schedule,
                                   const CompensatorSettings& s) {
  std::string g;
  for (const auto& p : schedule) {
    const std::string k = format_number(p.k_s, detail::kDecimalsK);
    const std::string flow = format_number(p.flow_mm3_s, 2);
    switch (fw) {
      case ExportFirmware::klipper:
      case ExportFirmware::kalico:
        g += fmt::format("SET_PRESSURE_ADVANCE{} ADVANCE={} ; at {} mm^3/s\n",
                         s.klipper_extruder != "extruder" ? " EXTRUDER=" + s.klipper_extruder : std::string(), k, flow);
        break;
      case ExportFirmware::marlin: g += fmt::format("M900 K{} ; at {} mm^3/s\n", k, flow); break;
      case ExportFirmware::rrf: g += fmt::format("M572 D{} S{} ; at {} mm^3/s\n", s.rrf_drive, k, flow); break;
    }
  }
  return g;
}

namespace detail {

const ShaperSetting* rrf_single_shaper(const CompensatorSettings& s, std::vector<std::string>& warnings,
                                       std::string* axis) {
  const auto x = s.shapers.find("x");
  const auto y = s.shapers.find("y");
  const ShaperSetting* xs = x != s.shapers.end() ? &x->second : nullptr;
  const ShaperSetting* ys = y != s.shapers.end() ? &y->second : nullptr;
  if (!xs && !ys) return nullptr;
  if (xs && ys) {
    const bool same = canonical_shaper_type(xs->type) == canonical_shaper_type(ys->type) &&
                      format_number(xs->freq_hz, kDecimalsFreq) == format_number(ys->freq_hz, kDecimalsFreq) &&
                      format_number(xs->damping, kDecimalsZeta) == format_number(ys->damping, kDecimalsZeta);
    const bool use_y = ys->freq_hz < xs->freq_hz;
    if (!same)
      warnings.push_back(fmt::format(
          "RepRapFirmware applies one input shaper to all axes: wrote {}'s ({} {} Hz, the lower frequency); "
          "{}'s {} {} Hz is lost",
          use_y ? "Y" : "X", (use_y ? ys : xs)->type, format_number((use_y ? ys : xs)->freq_hz, kDecimalsFreq),
          use_y ? "X" : "Y", (use_y ? xs : ys)->type, format_number((use_y ? xs : ys)->freq_hz, kDecimalsFreq)));
    if (axis) *axis = use_y ? "y" : "x";
    return use_y ? ys : xs;
  }
  if (axis) *axis = xs ? "x" : "y";
  return xs ? xs : ys;
}

}  // namespace detail
}  // namespace tunekit::firmware
