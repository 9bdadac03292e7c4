#pragma once
// What `tunekit resonance` and `tunekit shaper` share: the accelerometer inputs they read
// (Klipper's raw CSVs and spectrum files, RepRapFirmware's M956 files, Shake&Tune's .stdata,
// generic CSVs) and the pipeline files -> per-axis Welch spectra -> modes (natural frequency in
// Hz, damping ratio) that both run. The defaults are the library's: Klipper's Welch preset
// (ident::klipper_welch_options(): Kaiser window, beta 6, 50 % overlap, mean removed per
// segment) and ident::ResonanceOptions (modes searched in 10..133.33 Hz, where Klipper's sweep
// ends).

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/ident/resonance.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::calibration {

/// The accelerometer files and how their spectra and modes are computed.
struct AccelFilesOptions {
  std::vector<std::string> files;  ///< accelerometer CSVs, Klipper spectrum files, .stdata files
  /// Raw accelerometer CSVs, each with its commanded motion beside it, whose fit against that
  /// motion refines the dominant mode of its axis in place of the first of `files` (their spectra
  /// are not averaged with the others', the other modes stay the spectrum's): a second, slower
  /// sweep over the band of the mode the first located.
  std::vector<std::string> refine_files;
  /// Columns (time in s, accelerations in mm/s^2), the axis of every file (0: from the Klipper
  /// file name) and the sensor range for clipping detection.
  ident::AccelInputOptions input;
  ident::WelchOptions welch = ident::klipper_welch_options();  ///< PSD estimate (Klipper's preset)
  ident::ResonanceOptions modes;                               ///< band (Hz), most modes, peak threshold, FRF use
  double max_plot_hz = 200.0;                                  ///< highest frequency of the PSD arrays in the JSON, Hz
  /// Each input's SHA-256 for the JSON envelope's provenance (about 10 ms of a core for a 20 MB
  /// file); a command whose results go only to the terminal leaves the digests empty.
  bool digest_inputs = true;
};

/// The spectra and modes of one axis (or of one record whose axis is not known).
struct AxisResult {
  char axis = 0;                              ///< 'x', 'y', 'z', or 0 when no axis was named
  std::string label;                          ///< the axis letter, or the file stem when the axis is not known
  ident::AxisSpectrum spectrum;               ///< the datasets averaged (for the modes)
  std::vector<ident::AxisSpectrum> datasets;  ///< every recording / file dataset of the axis, as read
  ident::AxisModes modes;
};

/// What analyze_accel_files() found.
struct AccelAnalysis {
  std::vector<AxisResult> axes;       ///< ordered by label (x, y, z first)
  std::vector<InputDigest> inputs;    ///< every file, in the order given
  std::vector<std::string> warnings;  ///< the readers', the spectra's and the mode fits' ("axis x: ...")
  /// Records taken for a ring-down analysis instead (see analyze_accel_files()).
  std::vector<ident::AccelRecord> ringdown_records;
};

/// Which records go to a ring-down (free decay) analysis instead of the Welch pipeline.
enum class RingdownDiversion {
  none,       ///< every record is a spectrum (`tunekit shaper`)
  too_short,  ///< records shorter than two Welch segments (warned about)
  all,        ///< every generic CSV record (`tunekit resonance --ringdown`)
};

/// Work on an axis that does not need its modes, run on another thread while they are
/// identified: it may read the axis's label, spectrum and datasets, not its modes, and must not
/// throw (it keeps its own errors for its caller to report after the analysis).
using BesideModes = std::function<void(const AxisResult&)>;

/// Checks the options (InputError, exit 2), reads every file, groups the spectra by axis (a file
/// whose name names no axis, without an axis in the options, is its own group under its file
/// stem), averages each group and identifies its modes; `beside`, when given, runs for each axis
/// beside its mode fit and has finished when this returns.
AccelAnalysis analyze_accel_files(const AccelFilesOptions& options,
                                  RingdownDiversion ringdown = RingdownDiversion::none, const BesideModes& beside = {});

/// The label of a record: its axis letter, or its file stem.
std::string record_label(char axis, const std::string& path);

/// "none", "constant" or "linear" (the words --detrend takes).
std::string detrend_name(ident::Detrend d);
/// Parses "none", "constant" (or "mean") or "linear", case-insensitive; InputError otherwise.
ident::Detrend parse_detrend_name(const std::string& s);
/// Parses "x", "y" or "z" (either case) into the axis letter, "" into 0; InputError otherwise.
char parse_axis_name(const std::string& s);

}  // namespace tunekit::calibration
