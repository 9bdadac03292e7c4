#pragma once
// Klipper's vibration spectrum files, read and written as Klipper's own calibrate_shaper.py
// reads and writes them (Butyugin and O'Connor, Klipper, scripts/calibrate_shaper.py and
// klippy/extras/shaper_calibrate.py, 2020-2025).
//
// A spectrum file is a CSV whose header (the first line not starting with '#') starts with
// `freq,`. Klipper writes two layouts:
//   * one dataset:   `freq,psd_x,psd_y,psd_z,psd_xyz` -- TEST_RESONANCES (resonances_<axis>_*.csv),
//                    SHAPER_CALIBRATE (calibration_data_<axis>_*.csv), `calibrate_shaper.py -c`;
//   * several:       `freq,<name 1>,<name 2>,...` -- one summed PSD per recording, written by
//                    `calibrate_shaper.py -c` when it was given several files.
// Either may continue with `,shapers:,zv(54.2),mzv(...),...`: the shaper response columns.
// Klipper writes the PSDs of a file WITH those columns after dividing them by (f + 0.1 Hz) and
// damping them below 10 Hz ("normalized to frequencies"); a file WITHOUT them holds the PSD as
// measured, (mm/s^2)^2/Hz, and the reader applies that normalization itself before choosing a
// shaper. Frequencies are written rounded to 0.1 Hz and PSDs to 4 significant digits.

#include <string>
#include <string_view>
#include <vector>

#include "tunekit/ident/resonance.hpp"

namespace tunekit::ident {

/// True when the text is a Klipper spectrum file: its header line (the first line that is not
/// blank and not a '#' comment) starts with "freq," (case-insensitive).
bool is_klipper_spectrum(std::string_view bytes);

struct KlipperSpectrumFile {
  /// One spectrum per dataset. The one-dataset layout fills psd_x/psd_y/psd_z and psd_sum
  /// (from psd_xyz); the several-datasets layout fills psd_sum only. Each carries
  /// klipper_normalized = has_shapers, and files = {path} (one dataset) or {column name}.
  std::vector<AxisSpectrum> datasets;
  std::vector<std::string> dataset_names;   ///< "psd_xyz", or the names in the header
  bool has_shapers = false;                 ///< the header has a `shapers:` column
  std::vector<std::string> shaper_columns;  ///< e.g. "mzv(56.6)", as written
};

/// Reads a spectrum file already in memory. `axis` ('x', 'y', 'z' or 0: from the file name).
/// InputError (exit 2) located at FILE:LINE for a missing column, a non-numeric or negative
/// PSD value, non-increasing frequencies, fewer than 8 rows, or a PSD that is zero everywhere.
KlipperSpectrumFile read_klipper_spectrum(const std::string& path, std::string_view bytes, char axis);

/// One dataset to write: a name (the several-datasets header) and its PSDs on its own bins.
struct KlipperSpectrumColumn {
  std::string name;
  const AxisSpectrum* spectrum = nullptr;
};

/// One shaper response column: `name(freq)` in the header and its value per written row.
struct KlipperShaperColumn {
  std::string name;  ///< "zv", "mzv", ...
  double freq_hz = 0;
  std::vector<double> response;  ///< per row of the written frequency grid
};

/// Writes a spectrum file in Klipper's layout (`%.1f` frequencies, `%.3e` PSDs, `%.3f` shaper
/// responses), rows below max_freq_hz. One dataset: its own bins and psd_x/y/z/xyz (psd_x/y/z
/// are written as 0 where the spectrum has none). Several: every PSD interpolated onto a 0.2 Hz
/// grid from the lowest first bin, one column per dataset (names quoted as Klipper does).
/// Klipper reads a file with shaper columns as already normalized, one without as measured: pass
/// normalized PSDs (klipper_normalize) together with shapers, measured ones without. Each shaper's
/// response has one value per row, on the grid klipper_spectrum_grid gives.
std::string write_klipper_spectrum(const std::vector<KlipperSpectrumColumn>& datasets,
                                   const std::vector<KlipperShaperColumn>& shapers, double max_freq_hz = 200.0);

/// The frequencies (Hz) of the rows write_klipper_spectrum writes for these datasets.
std::vector<double> klipper_spectrum_grid(const std::vector<KlipperSpectrumColumn>& datasets,
                                          double max_freq_hz = 200.0);

}  // namespace tunekit::ident
