#pragma once
// tunekit delta as a function: least-squares calibration of a linear delta's geometric errors
// from probe heights (after Brown, Delta Printer Project Report, La Trobe University, 2013), with
// the factor sets of the firmwares' own auto-calibrations, and the fitted settings for Klipper,
// Marlin or RepRapFirmware. The shape of a command is described in docs/cpp-api.md.

#include <array>
#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/delta_calibration.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration {

/// Three per-tower values (A, B, C) as the command line's list.
inline std::vector<double> delta_tower_values(const std::array<double, 3>& v) { return {v.begin(), v.end()}; }

struct DeltaOptions {
  std::string probes_csv;  ///< probe heights: x_mm, y_mm, z_mm (G30 S-1 trigger heights)
  int factors = 6;         ///< 3, 4, 6, 7, 8 or 9 (ident::kDeltaFactorChoices); 6 is Klipper's set
  // The geometry the firmware ran while probing (mm, degrees).
  double radius_mm = fitting::kNaN;  ///< delta radius; required
  std::vector<double> rod_mm;        ///< diagonal rod length, one or three values; required
  double height_mm = fitting::kNaN;  ///< homed height H; required
  /// Tower angles A, B, C (deg) and endstop adjustments (mm), three values each; the defaults
  /// are the library's nominal geometry.
  std::vector<double> angles_deg = delta_tower_values(ident::DeltaGeometry{}.angle_deg);
  std::vector<double> endstops_mm = delta_tower_values(ident::DeltaGeometry{}.endstop_mm);
  std::string export_firmware;             ///< klipper, marlin, rrf (or kalico); empty: no export
  std::string export_file;                 ///< the export is written here (atomically); empty: printed
  double print_radius_mm = fitting::kNaN;  ///< RepRapFirmware's M665 B (mm)
  double marlin_probe_z_offset_mm = 0.0;   ///< Marlin's M851 Z (mm)
  std::size_t max_rows = 200000;           ///< most probe rows accepted (count; --max-rows)
};

struct DeltaOutcome {
  DeltaOptions options;
  InputDigest input;                                 ///< the probe CSV
  std::size_t probe_count = 0;                       ///< probe points read
  ident::DeltaCalibration calibration;               ///< factors, nominal and fitted geometry, flatness, residuals
  std::optional<firmware::ExportFirmware> firmware;  ///< the export's firmware when asked for
  std::string export_text;                           ///< the fitted settings in that firmware's syntax
  std::vector<std::string> warnings;
};

/// Fits the factors and renders (and with export_file writes) the export. InputError (exit 2)
/// for bad options or input, FitError (exit 1) when the fit does not converge.
DeltaOutcome compute_delta(const DeltaOptions& options);

Envelope to_envelope(const DeltaOutcome& outcome);
void print_text(const DeltaOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
