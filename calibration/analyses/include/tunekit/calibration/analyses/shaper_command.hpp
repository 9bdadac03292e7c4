#pragma once
// tunekit shaper as a function: input shapers designed and recommended per axis from
// accelerometer data. By default the shapers are designed for the identified damping ratio
// and their remaining vibrations evaluated over its 95 % interval; klipper_compatible
// reproduces the selection of Klipper's calibrate_shaper.py (Butyugin, 2020: assumed damping
// 0.1, vibrations pessimized over 0.075/0.1/0.15). The shape of a command is described in
// docs/cpp-api.md.

#include <cstddef>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/design/input_shaper.hpp"
#include "tunekit/firmware/firmware_export.hpp"

namespace tunekit::calibration {

/// Klipper's calibrate_shaper.py tries shaper frequencies below 150 Hz (MAX_SHAPER_FREQ in
/// klippy/extras/shaper_calibrate.py); tunekit's own selection looks up to the library's
/// design::ShaperSelectionOptions::max_shaper_freq_hz.
inline constexpr double kKlipperMaxShaperFreqHz = 150.0;

struct ShaperOptions {
  /// The files (and, for generic CSVs, their columns); spectra and modes as `tunekit resonance`.
  AccelFilesOptions accel;
  /// Select as Klipper's calibrate_shaper.py does instead of from the identified damping.
  bool klipper_compatible = false;
  /// Shaper types considered; empty: all seven (identified damping) or the library's default
  /// list, Klipper's (klipper_compatible, or an axis without an identified mode).
  std::vector<design::ShaperType> shapers;
  /// scv_mm_s (square-corner velocity, mm/s), max_smoothing_mm (0: no limit), max_vibrations
  /// (fraction, 0: no limit; 0.001 to 1 otherwise) and max_freq_hz
  /// (highest PSD frequency scored, Hz) are used as given. Its max_shaper_freq_hz is the highest
  /// shaper frequency tried without klipper_compatible, its design_damping_ratio and
  /// test_damping_ratios are Klipper's assumed damping; types and the damping ratios are set
  /// per axis by compute_shaper().
  design::ShaperSelectionOptions selection;
  /// Design damping ratio (dimensionless, below 1); <= 0: the identified one (Klipper's assumed
  /// damping with klipper_compatible).
  double damping_ratio = -1;
  /// Shaper frequencies tried stay below this, Hz; <= 0: selection.max_shaper_freq_hz, or
  /// Klipper's 150 Hz with klipper_compatible.
  double max_shaper_freq_hz = -1;
  /// Also write each axis's spectrum and shaper responses in Klipper's calibration_data layout
  /// to this path ("{axis}" becomes the axis label); empty: none.
  std::string klipper_csv;
  /// Recommend among this firmware's shapers only, each within its damping bound. Unset (and
  /// no `shapers` given): Klipper is assumed, so that the recommendation is one Klipper
  /// accepts; with `shapers` given, they are compared as asked.
  std::optional<firmware::ExportFirmware> firmware;
  /// The printer's acceleration limit on the axes, mm/s^2 (0: not known). The proposed maximum
  /// acceleration is the shaper's (the highest its smoothing allows) capped by it.
  double accel_limit_mm_s2 = 0;
};

/// One axis (or one record whose axis is not known) and the shaper chosen for it.
struct ShaperAxis {
  AxisResult resonance;         ///< label ("x", "y", "z" or the file stem), spectra and modes
  bool klipper_method = false;  ///< selected with Klipper's assumed damping (asked, or no mode identified)
  /// The selection as run: types, design and test damping ratios, max_shaper_freq_hz, ...
  design::ShaperSelectionOptions selection;
  /// The recommended shaper (recommended.type, freq_hz in Hz, damping_ratio: the firmware
  /// settings) and every type's best candidate.
  design::ShaperSelection choice;
  std::size_t datasets = 0;          ///< recordings (or spectrum datasets) the shapers were scored on
  std::size_t normalized_by_us = 0;  ///< of them, normalized by tunekit (the rest by Klipper)
  std::string klipper_csv;           ///< the Klipper layout file written for this axis; empty: none
};

struct ShaperOutcome {
  ShaperOptions options;
  double max_shaper_freq_hz = 0;  ///< as used (the default resolved), Hz
  /// The firmware recommended for: options.firmware, or Klipper when assumed; none when
  /// the shapers given were compared without a firmware.
  std::optional<firmware::ExportFirmware> firmware;
  bool firmware_assumed = false;  ///< Klipper assumed: no --firmware and no --shapers
  std::vector<InputDigest> inputs;
  std::vector<ShaperAxis> axes;       ///< ordered by label (x, y, z first)
  std::vector<std::string> warnings;  ///< the pipeline's, then per axis

  /// The axis with this label ("x", "y", ...), or nullptr.
  const ShaperAxis* axis(const std::string& label) const;
};

/// Reads the files, identifies each axis's modes, selects its shaper and writes the
/// klipper_csv files (all or none, after every axis succeeded). InputError (exit 2) for bad
/// options or input, FitError (exit 1) when a fit fails.
ShaperOutcome compute_shaper(const ShaperOptions& options);

/// The envelope: results.axes.<label> holds modes, fit, recommended, candidates, selection,
/// psd and (for an identified mode) freq_hz and zeta of the dominant mode.
Envelope to_envelope(const ShaperOutcome& outcome);
/// One axis' results as to_envelope() writes them under results.axes.LABEL: modes (Hz, damping
/// ratio), fit, recommended shaper, candidates, selection, PSD.
nlohmann::json shaper_axis_json(const ShaperOutcome& outcome, const ShaperAxis& axis);
/// The maximum acceleration (mm/s^2) proposed with an axis' recommended shaper: the shaper's own
/// (rounded as Klipper suggests it), or the printer's limit when the shaper allows more (`capped`).
struct ProposedAccel {
  double mm_s2 = 0;
  bool capped = false;
};
ProposedAccel proposed_max_accel(const ShaperOutcome& outcome, const ShaperAxis& axis);
void print_text(const ShaperOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
