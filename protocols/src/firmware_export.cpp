#include "tunekit/protocols/firmware_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "tunekit/fitting/error.hpp"
#include "tunekit/protocols/config_edit.hpp"
#include "text_util.hpp"

namespace tunekit::protocols {
namespace {

// Accepted ranges (docs/export.md gives the sources).
constexpr double kMarlinKMax = 10.0;           // M900: K outside 0-10 is rejected
constexpr double kMarlinTauMax = 0.5;          // M900 U (SMOOTH_LIN_ADVANCE): 0-0.5 s
constexpr double kKlipperSmoothMax = 0.2;      // pressure_advance_smooth_time: above 0, at most 0.200 s
constexpr double kRrfFreqMin = 937500.0 / (2 * 65535.0);  // 16-bit half period at the Duet 2 step clock
constexpr double kRrfFreqMax = 1000.0;
constexpr double kRrfZetaMax = 0.99;

}  // namespace

ExportFirmware parse_export_firmware(const std::string& name) {
  const std::string n = text::lower(name);
  if (n == "klipper") return ExportFirmware::klipper;
  if (n == "marlin") return ExportFirmware::marlin;
  if (n == "rrf" || n == "reprapfirmware" || n == "duet") return ExportFirmware::rrf;
  throw InputError(fmt::format("unknown firmware '{}': use klipper, marlin or rrf", name));
}

std::string to_string(ExportFirmware fw) {
  switch (fw) {
    case ExportFirmware::klipper: return "klipper";
    case ExportFirmware::marlin: return "marlin";
    case ExportFirmware::rrf: return "rrf";
  }
  return "?";
}

std::string canonical_shaper_type(const std::string& type) {
  const std::string t = text::lower(type);
  if (t == "ei2" || t == "2hei" || t == "2-hump-ei") return "2hump_ei";
  if (t == "ei3" || t == "3hei" || t == "3-hump-ei") return "3hump_ei";
  return t;
}

std::string firmware_shaper_name(ExportFirmware fw, const std::string& type) {
  const std::string t = canonical_shaper_type(type);
  switch (fw) {
    case ExportFirmware::klipper: {
      static const char* known[] = {"zv", "mzv", "zvd", "ei", "2hump_ei", "3hump_ei"};
      for (const char* k : known)
        if (t == k) return t;
      throw InputError(fmt::format("Klipper has no '{}' input shaper (it has zv, mzv, zvd, ei, 2hump_ei, 3hump_ei)", type));
    }
    case ExportFirmware::marlin:
      if (t == "zv") return "zv";
      throw InputError(fmt::format("Marlin's input shaping is ZV only; '{}' is not available (choose zv)", type));
    case ExportFirmware::rrf:
      if (t == "mzv" || t == "zvd" || t == "zvdd" || t == "zvddd") return t;
      if (t == "2hump_ei") return "ei2";
      if (t == "3hump_ei") return "ei3";
      throw InputError(fmt::format(
          "RepRapFirmware has no '{}' input shaper (it has mzv, zvd, zvdd, zvddd, ei2, ei3)", type));
  }
  throw InputError("unknown firmware");
}

void validate_settings(ExportFirmware fw, const CompensatorSettings& s) {
  std::vector<std::string> bad;
  const std::string name = fw == ExportFirmware::klipper ? "Klipper" : fw == ExportFirmware::marlin ? "Marlin" : "RepRapFirmware";
  if (s.pa_k_s) {
    const double k = *s.pa_k_s;
    if (!std::isfinite(k) || k < 0)
      bad.push_back(fmt::format("advance K {} s is negative or not a number", k));
    else if (fw == ExportFirmware::marlin && k > kMarlinKMax)
      bad.push_back(fmt::format("Marlin accepts K from 0 to {} (M900 K); {} is out of range", kMarlinKMax, k));
  }
  if (s.pa_smooth_s) {
    const double t = *s.pa_smooth_s;
    if (!std::isfinite(t) || t < 0)
      bad.push_back(fmt::format("smoothing time {} s is negative or not a number", t));
    else if (fw == ExportFirmware::klipper && (t <= 0 || t > kKlipperSmoothMax))
      bad.push_back(fmt::format("Klipper accepts pressure_advance_smooth_time above 0 and up to {} s; {} is out of range",
                                kKlipperSmoothMax, t));
    else if (fw == ExportFirmware::marlin && t > kMarlinTauMax)
      bad.push_back(fmt::format("Marlin accepts ADVANCE_TAU (M900 U) from 0 to {} s; {} is out of range", kMarlinTauMax, t));
  }
  for (const auto& [axis, sh] : s.shapers) {
    if (axis != "x" && axis != "y") {
      bad.push_back(fmt::format("input shaping on axis '{}' is not exported (x and y only)", axis));
      continue;
    }
    try {
      firmware_shaper_name(fw, sh.type);
    } catch (const InputError& e) {
      bad.push_back(fmt::format("{}: {}", axis, e.message()));
    }
    if (!std::isfinite(sh.freq_hz) || sh.freq_hz <= 0)
      bad.push_back(fmt::format("{}: shaper frequency must be positive, not {} Hz", axis, sh.freq_hz));
    else if (fw == ExportFirmware::rrf && (sh.freq_hz < kRrfFreqMin || sh.freq_hz > kRrfFreqMax))
      bad.push_back(fmt::format("{}: RepRapFirmware accepts shaper frequencies from {:.2f} to {:.0f} Hz; {} is out of range",
                                axis, kRrfFreqMin, kRrfFreqMax, sh.freq_hz));
    if (!std::isfinite(sh.damping) || sh.damping < 0 || sh.damping >= 1)
      bad.push_back(fmt::format("{}: damping ratio must be at least 0 and below 1, not {}", axis, sh.damping));
    else if (fw == ExportFirmware::rrf && sh.damping > kRrfZetaMax)
      bad.push_back(fmt::format("{}: RepRapFirmware accepts damping up to {}; {} is out of range", axis, kRrfZetaMax,
                                sh.damping));
  }
  if (!bad.empty()) {
    std::string msg = fmt::format("refusing to write {} settings: ", name);
    for (std::size_t i = 0; i < bad.size(); ++i) msg += (i ? "; " : "") + bad[i];
    throw InputError(msg);
  }
}

ExportResult export_config_text(ExportFirmware fw, const std::string& text, const std::string& path,
                                const CompensatorSettings& s) {
  validate_settings(fw, s);
  ExportResult r;
  r.firmware = fw;
  r.path = path;
  r.original = text;
  static const std::map<ExportFirmware, std::vector<std::string>> kCommentMarkers = {
      {ExportFirmware::klipper, {"#", ";"}}, {ExportFirmware::marlin, {"//"}}, {ExportFirmware::rrf, {";"}}};
  const ScopedCommentNote note(kCommentMarkers.at(fw), s.change_note);
  switch (fw) {
    case ExportFirmware::klipper: detail::write_klipper(r, s); break;
    case ExportFirmware::marlin: detail::write_marlin(r, s); break;
    case ExportFirmware::rrf: detail::write_rrf(r, s); break;
  }
  return r;
}

ExportResult export_config_file(ExportFirmware fw, const std::string& path, const CompensatorSettings& s) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot read the configuration file", path);
  std::stringstream ss;
  ss << in.rdbuf();
  return export_config_text(fw, ss.str(), path, s);
}

std::string apply_export(const ExportResult& r, const std::function<void(const std::string&)>& before_rename) {
  if (!r.changed()) return {};
  // Refuse to overwrite a file that changed since it was read.
  std::ifstream in(r.path, std::ios::binary);
  if (!in) throw InputError("cannot read the configuration file", r.path);
  std::stringstream ss;
  ss << in.rdbuf();
  if (ss.str() != r.original)
    throw InputError("the configuration file changed since it was read; run the export again", r.path);
  return write_with_backup(r.path, r.updated, before_rename);
}

nlohmann::json ExportResult::to_json() const {
  nlohmann::json ch = nlohmann::json::array();
  for (const auto& c : changes)
    ch.push_back({{"key", c.key}, {"old", c.old_value}, {"new", c.new_value}, {"line", c.line}, {"where", c.where}});
  return {{"firmware", to_string(firmware)}, {"config", path},         {"changed", changed()},
          {"changes", ch},                  {"warnings", warnings},    {"diff", diff},
          {"gcode", gcode}};
}

std::optional<double> smoothing_time_for(ExportFirmware fw, const ident::AdvanceDesign& d) {
  double w = ident::kAdvanceNaN;
  if (fw == ExportFirmware::klipper) w = d.window_triangular_s;
  if (fw == ExportFirmware::marlin) w = d.window_box_s;
  if (!std::isfinite(w) || w <= 0) return std::nullopt;
  const double scale = std::pow(10.0, detail::kDecimalsSmooth);
  return std::max(1.0 / scale, std::ceil(w * scale - 1e-9) / scale);
}

std::string advance_schedule_gcode(ExportFirmware fw, const std::vector<ident::ScheduledAdvance>& schedule,
                                   const CompensatorSettings& s) {
  std::string g;
  for (const auto& p : schedule) {
    const std::string k = format_number(p.k_s, detail::kDecimalsK);
    const std::string flow = format_number(p.flow_mm3_s, 2);
    switch (fw) {
      case ExportFirmware::klipper:
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
}  // namespace tunekit::protocols
