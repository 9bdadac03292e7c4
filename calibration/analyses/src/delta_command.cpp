// tunekit delta: least-squares calibration of a linear delta's geometric errors from probe
// heights (after Brown, "Delta Printer Project Report", La Trobe University, 2013), with
// the factor sets of the firmwares' own auto-calibrations, and export to Klipper, Marlin
// and RepRapFirmware.
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/delta_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/row_limit.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/delta_calibration.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/delta_export.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/core/file_bytes.hpp"

namespace tunekit::calibration {
namespace {

const formats::CsvColumn& delta_column(const formats::CsvTable& t, const std::string& axis, const std::string& hdr) {
  for (const std::string& n : {axis, axis + "_mm"})
    if (t.has_column(n)) {
      const auto& c = t.column(n);
      if (!(c.unit.empty() || c.unit == "mm")) throw InputError(fmt::format("column '{}' must be in mm", n), hdr);
      return c;
    }
  throw InputError(fmt::format("no '{0}_mm' (or '{0} (mm)') column; the probe CSV has x_mm,y_mm,z_mm", axis), hdr);
}

ident::DeltaGeometry delta_nominal(const DeltaOptions& a) {
  if (!(a.radius_mm > 0)) throw InputError("give the firmware's delta radius: --radius (mm, > 0)");
  if (!std::isfinite(a.height_mm)) throw InputError("give the firmware's homed height: --height (mm)");
  if (a.rod_mm.size() != 1 && a.rod_mm.size() != 3)
    throw InputError("give the diagonal rod length: --rod L or --rod LA,LB,LC (mm)");
  if (a.angles_deg.size() != 3 || a.endstops_mm.size() != 3)
    throw InputError("--angles and --endstops take three values (towers A, B, C)");
  ident::DeltaGeometry g;
  g.radius_mm = a.radius_mm;
  g.homed_height_mm = a.height_mm;
  for (std::size_t i = 0; i < 3; ++i) {
    g.rod_mm[i] = a.rod_mm.size() == 1 ? a.rod_mm[0] : a.rod_mm[i];
    if (!(std::isfinite(g.rod_mm[i]) && g.rod_mm[i] > g.radius_mm))
      throw InputError("--rod must be longer than --radius (mm)");
    g.angle_deg[i] = a.angles_deg[i];
    g.endstop_mm[i] = a.endstops_mm[i];
    if (!std::isfinite(g.angle_deg[i]) || !std::isfinite(g.endstop_mm[i]))
      throw InputError("--angles and --endstops must be finite");
  }
  return g;
}

nlohmann::json delta_geometry_json(const ident::DeltaGeometry& g) {
  return {{"delta_radius_mm", g.radius_mm},       {"diagonal_rod_mm", g.rod_mm},
          {"tower_angle_deg", g.angle_deg},       {"endstop_adjustment_mm", g.endstop_mm},
          {"homed_height_mm", g.homed_height_mm}, {"tilt_x_percent", g.tilt_x * 100.0},
          {"tilt_y_percent", g.tilt_y * 100.0}};
}

nlohmann::json delta_flatness_json(const ident::DeltaFlatness& f) {
  return {{"rms_mm", f.rms_mm}, {"std_mm", f.std_mm}, {"peak_to_peak_mm", f.peak_to_peak_mm}};
}

}  // namespace

DeltaOutcome compute_delta(const DeltaOptions& a) {
  DeltaOutcome outcome;
  outcome.options = a;
  (void)ident::delta_factor_names(a.factors);
  const auto nominal = delta_nominal(a);
  if (!a.export_firmware.empty()) outcome.firmware = firmware::parse_export_firmware(a.export_firmware);
  if (!a.export_file.empty() && a.export_firmware.empty()) throw InputError("--export-file needs --export FIRMWARE");

  const std::string bytes = read_file_bytes(a.probes_csv);
  outcome.input = input_digest(a.probes_csv, bytes);
  require_line_limit(bytes, a.max_rows, "--max-rows", a.probes_csv);
  const auto t = formats::parse_csv(bytes, a.probes_csv);
  require_row_limit(t.rows, a.max_rows, "--max-rows", a.probes_csv);
  const auto hdr = source_location(a.probes_csv, t.header_line);
  const auto &xc = delta_column(t, "x", hdr), &yc = delta_column(t, "y", hdr), &zc = delta_column(t, "z", hdr);
  std::vector<ident::DeltaProbe> probes;
  for (std::size_t i = 0; i < t.rows; ++i) probes.push_back({xc.values[i], yc.values[i], zc.values[i]});
  outcome.probe_count = probes.size();

  outcome.calibration = ident::fit_delta_calibration(nominal, probes, a.factors);
  const auto& cal = outcome.calibration;
  if (outcome.firmware) {
    switch (*outcome.firmware) {
      case firmware::ExportFirmware::kalico:
      case firmware::ExportFirmware::klipper:
        outcome.export_text = firmware::delta_klipper_save_config(cal.fitted);
        break;
      case firmware::ExportFirmware::marlin:
        outcome.export_text = firmware::delta_marlin_gcode(cal.fitted, a.marlin_probe_z_offset_mm);
        break;
      case firmware::ExportFirmware::rrf:
        outcome.export_text = firmware::delta_rrf_gcode(cal.fitted, a.print_radius_mm);
        break;
    }
  }
  outcome.warnings = cal.fit.warnings;
  if (!a.export_file.empty()) core::write_file_atomic(a.export_file, outcome.export_text);
  return outcome;
}

Envelope to_envelope(const DeltaOutcome& o) {
  const DeltaOptions& a = o.options;
  const auto& cal = o.calibration;
  Envelope env("delta");
  env.set_options({{"factors", a.factors}, {"export", a.export_firmware}, {"export_file", a.export_file}});
  add_input(env, o.input);
  auto& res = env.results();
  res = fitting::to_json(cal.fit);
  res["nominal"] = delta_geometry_json(cal.nominal);
  res["fitted"] = delta_geometry_json(cal.fitted);
  res["flatness_before"] = delta_flatness_json(cal.before);
  res["flatness_after"] = delta_flatness_json(cal.after);
  res["residual_mm"] = cal.residual_mm;
  if (o.firmware && !o.export_text.empty())
    res["export"] = {{"firmware", firmware::to_string(*o.firmware)}, {"text", o.export_text}};
  for (const auto& w : o.warnings) env.warn(w);
  return env;
}

void print_text(const DeltaOutcome& o, std::ostream& os) {
  const DeltaOptions& a = o.options;
  const auto& cal = o.calibration;
  os << fmt::format("{}: {} probe points, {}-factor delta calibration\n", a.probes_csv, o.probe_count, a.factors);
  for (const auto& q : cal.fit.params)
    os << fmt::format("  {:<14} {:>12.4f} {:<4} +- {:.4f}  95% [{:.4f}, {:.4f}]\n", q.name, q.value, q.unit,
                      q.std_error, q.ci95_lo, q.ci95_hi);
  os << fmt::format("  flatness before: rms {:.4f} mm, peak-to-peak {:.4f} mm\n", cal.before.rms_mm,
                    cal.before.peak_to_peak_mm);
  os << fmt::format("  flatness after:  rms {:.4f} mm, peak-to-peak {:.4f} mm\n", cal.after.rms_mm,
                    cal.after.peak_to_peak_mm);
  if (o.firmware && !o.export_text.empty()) {
    if (a.export_file.empty()) os << o.export_text;
    else os << fmt::format("  {} settings written to {}\n", firmware::to_string(*o.firmware), a.export_file);
  }
}

}  // namespace tunekit::calibration
