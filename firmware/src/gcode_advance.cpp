#include "tunekit/firmware/gcode_advance.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "export_writers.hpp"
#include "gcode_words.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/fitting/interpolate.hpp"

namespace tunekit::firmware {
namespace {

std::string ga_set_command(const GcodeAdvanceOptions& o, double k, double q, const std::string& feature) {
  const std::string ks = format_number(k, detail::kDecimalsK);
  const std::string note = fmt::format(" ; tunekit: {} at {} mm^3/s", feature, format_number(q, 2));
  switch (o.firmware) {
    case ExportFirmware::klipper:
    case ExportFirmware::kalico:
      return "SET_PRESSURE_ADVANCE" +
             (o.klipper_extruder != "extruder" ? " EXTRUDER=" + o.klipper_extruder : std::string()) + " ADVANCE=" + ks +
             note;
    case ExportFirmware::marlin: return "M900 K" + ks + note;
    case ExportFirmware::rrf: return fmt::format("M572 D{} S{}{}", o.rrf_drive, ks, note);
  }
  return {};
}

}  // namespace

bool parse_advance_command(const std::string& line, ExportFirmware fw, double& k_s) {
  const std::string code = gcode_words::code(line);
  if (code.empty()) return false;
  const std::string cmd = gcode_words::command(code);
  std::optional<double> v;
  switch (fw) {
    case ExportFirmware::klipper:
    case ExportFirmware::kalico:
      if (cmd == "SET_PRESSURE_ADVANCE") v = gcode_words::param(code, "ADVANCE");
      break;
    case ExportFirmware::marlin:
      if (cmd == "M900") v = gcode_words::word(code, 'K');
      break;
    case ExportFirmware::rrf:
      if (cmd == "M572") v = gcode_words::word(code, 'S');
      break;
  }
  if (!v) return false;
  k_s = *v;
  return true;
}

namespace {

// The advance table sorted by flow, every value checked against the firmware's bounds first
// (it may be written).
std::vector<std::pair<double, double>> checked_advance_table(const GcodeAdvanceOptions& o) {
  std::vector<std::pair<double, double>> table = o.k_of_flow;
  std::sort(table.begin(), table.end());
  for (const auto& [q, k] : table) {
    CompensatorSettings s;
    s.pa_k_s = k;
    if (!std::isfinite(q)) throw InputError("advance table: a flow is not a number");
    validate_settings(o.firmware == ExportFirmware::kalico ? ExportFirmware::klipper : o.firmware, s);
  }
  return table;
}

// The filament's cross-section (mm^2): given, else from the file's '; filament_diameter = D'
// comment (the first extruder's value of "1.75,1.75"). InputError when neither gives one.
double filament_area_mm2(const LineEditor& ed, double given, const std::string& path) {
  double area = given;
  if (!(area > 0)) {
    for (std::size_t i = 0; i < ed.size(); ++i) {
      const std::string& t = ed.line(i);
      const auto p = t.find("filament_diameter");
      if (t.rfind(";", 0) != 0 || p == std::string::npos) continue;
      const auto eq = t.find_first_of("=:", p);
      if (eq == std::string::npos) continue;
      try {
        const double dmm = std::stod(t.substr(eq + 1));  // the first extruder's value ("1.75,1.75")
        if (dmm > 0 && std::isfinite(dmm)) {
          area = M_PI * dmm * dmm / 4;
          break;
        }
      } catch (const std::logic_error&) {
      }
    }
  }
  if (!(area > 0))
    throw InputError(
        "no filament diameter: the file has no '; filament_diameter = D' line and no machine profile gave one", path);
  return area;
}

// A feature block (from its ';TYPE:' line): its extrusion and its extrusion-weighted flow sum.
struct FeatureBlock {
  std::size_t type_line;
  std::string feature;
  double e_sum = 0, qe_sum = 0;
};

// Pass 1: the feature blocks and their extrusion-weighted flow (mm^3/s) from the moves' feed,
// length and extrusion. InputError when the file marks no feature.
std::vector<FeatureBlock> feature_blocks(const LineEditor& ed, double area, const std::string& path) {
  std::vector<FeatureBlock> blocks;
  bool rel_xy = false, rel_e = false;
  double x = 0, y = 0, e = 0, f = 0;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    const std::string& t = ed.line(i);
    if (t.rfind(";TYPE:", 0) == 0) {
      std::string feat = t.substr(6);
      while (!feat.empty() && (feat.back() == '\r' || feat.back() == ' ')) feat.pop_back();
      blocks.push_back({i, feat});
      continue;
    }
    const std::string code = gcode_words::code(t);
    if (code.empty()) continue;
    const std::string cmd = gcode_words::command(code);
    if (cmd == "G90") rel_xy = false;
    else if (cmd == "G91") rel_xy = true;
    else if (cmd == "M82") rel_e = false;
    else if (cmd == "M83") rel_e = true;
    else if (cmd == "G92") {
      if (auto v = gcode_words::word(code, 'E')) e = *v;
      if (auto v = gcode_words::word(code, 'X')) x = *v;
      if (auto v = gcode_words::word(code, 'Y')) y = *v;
    } else if (cmd == "G0" || cmd == "G1" || cmd == "G00" || cmd == "G01") {
      const double x0 = x, y0 = y;
      if (auto v = gcode_words::word(code, 'X')) x = rel_xy ? x + *v : *v;
      if (auto v = gcode_words::word(code, 'Y')) y = rel_xy ? y + *v : *v;
      if (auto v = gcode_words::word(code, 'F')) f = *v;
      double de = 0;
      if (auto v = gcode_words::word(code, 'E')) {
        de = rel_e ? *v : *v - e;
        e = rel_e ? e + *v : *v;
      }
      const double dxy = std::hypot(x - x0, y - y0);
      if (de > 0 && dxy > 1e-9 && f > 0 && !blocks.empty()) {
        const double q = de / dxy * area * f / 60.0;
        blocks.back().e_sum += de;
        blocks.back().qe_sum += q * de;
      }
    }
  }
  if (blocks.empty())
    throw InputError(
        "no ';TYPE:' feature comments: slice with PrusaSlicer, OrcaSlicer or Cura (they mark every feature)", path);
  return blocks;
}

}  // namespace

GcodeAdvanceResult apply_gcode_advance(const std::string& text, const GcodeAdvanceOptions& o, const std::string& path) {
  if (o.k_of_flow.empty()) throw InputError("no advance table for the G-code post-processor");
  if (!(std::isfinite(o.hysteresis) && o.hysteresis >= 0 && o.hysteresis < 1))
    throw InputError(fmt::format("hysteresis must be at least 0 and below 1, not {}", o.hysteresis));
  const std::vector<std::pair<double, double>> table = checked_advance_table(o);
  std::vector<double> table_q, table_k;  // the table as columns for fitting::interp_linear
  for (const auto& [q, k] : table) table_q.push_back(q), table_k.push_back(k);
  const LineEditor ed(text);
  const double area = filament_area_mm2(ed, o.filament_area_mm2, path);
  const std::vector<FeatureBlock> blocks = feature_blocks(ed, area, path);

  // Pass 2: decide the changes (with the file's own advance commands in order).
  GcodeAdvanceResult r;
  LineEditor out(text);
  double active = std::nan("");
  std::size_t next_block = 0;
  for (std::size_t i = 0; i < ed.size(); ++i) {
    double k_file = 0;
    if (parse_advance_command(ed.line(i), o.firmware, k_file)) active = k_file;
    if (next_block < blocks.size() && blocks[next_block].type_line == i) {
      const FeatureBlock& b = blocks[next_block++];
      if (b.e_sum <= 0) continue;
      ++r.features;
      const double q = b.qe_sum / b.e_sum;
      const double k = fitting::interp_linear(table_q, table_k, q);
      const std::string ks = format_number(k, detail::kDecimalsK);
      const bool change = !std::isfinite(active) || std::abs(k - active) > o.hysteresis * active;
      if (!change) continue;
      out.insert_before(i + 1, {ga_set_command(o, k, q, b.feature)});
      active = std::stod(ks);
      r.changes.push_back({i + 1, b.feature, q, active});
    }
  }
  r.text = out.render();
  return r;
}

}  // namespace tunekit::firmware
