#pragma once
// Shared by `tunekit resonance` and `tunekit shaper`: the input options (Klipper raw CSVs,
// calibration data, generic CSVs), the pipeline files -> per-axis spectra -> modes, and the
// JSON of modes and spectra.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tunekit/cli/context.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/ident/resonance.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::cli {

struct ResonanceCliArgs {
  std::vector<std::string> files;
  std::string axis;
  std::string time_column = "time";
  std::vector<std::string> accel_columns;
  std::string excitation_column;
  std::string window = "kaiser";
  double kaiser_beta = 6.0;
  std::size_t segment = 0;
  double overlap = 0.5;
  std::string detrend = "constant";
  double fit_min_hz = 10.0;
  double fit_max_hz = 133.33;
  int max_modes = 3;
  double peak_threshold = 0.05;
  double excitation_exponent = -1;
  double full_scale_mm_s2 = 0;
  double max_plot_hz = 200.0;
  bool no_frf = false;
  // Ring-down (free decay) analysis; see ident/ringdown.hpp.
  bool ringdown = false;           ///< analyse every file as a ring-down
  std::string ringdown_channel;    ///< channel to analyse; empty: the strongest
  double min_strength = 3.0;       ///< signal/noise RMS ratio below which a record is refused
  double ringdown_min_hz = 20.0;
  double ringdown_max_hz = 0.0;    ///< 0: 0.45 x sample rate
  OutputOptions output;
};

struct AxisResult {
  char axis = 0;       ///< 'x', 'y', 'z', or 0 when no axis was named
  std::string label;   ///< the axis letter, or the file stem when the axis is not known
  ident::AxisSpectrum spectrum;                ///< the datasets averaged (for the modes)
  std::vector<ident::AxisSpectrum> datasets;  ///< every recording / file dataset of the axis, as read
  ident::AxisModes modes;
};

/// Adds the input, spectrum and mode options.
void add_resonance_options(CLI::App* sub, ResonanceCliArgs& a);
/// Reads every file, groups by axis (a file whose name names no axis, without --axis, is its own
/// group under its file stem), computes spectra and modes; records inputs, options and warnings
/// in the envelope. Results are ordered by label (x, y, z first). Records too short for Welch's
/// method (or every record, with --ringdown) are moved to `ringdown_records` when it is given.
std::vector<AxisResult> run_resonance_pipeline(const ResonanceCliArgs& a, Envelope& env,
                                               std::vector<ident::AccelRecord>* ringdown_records = nullptr);
/// The ring-down options from the command line.
ident::RingdownOptions ringdown_options(const ResonanceCliArgs& a);
/// Adds the ring-down options (--ringdown, --channel, --min-strength, band).
void add_ringdown_options(CLI::App* sub, ResonanceCliArgs& a, bool with_flag);
/// The label of a record: its axis letter, or its file stem.
std::string record_label(char axis, const std::string& path);
/// The options as JSON (for the envelope).
nlohmann::json resonance_options_json(const ResonanceCliArgs& a);
/// modes[] as in the results contract.
nlohmann::json modes_json(const ident::AxisModes& m);
/// PSD (and FRF) arrays up to max_plot_hz for plotting.
nlohmann::json spectrum_json(const ident::AxisSpectrum& s, double max_plot_hz);
/// The fit's method, band, peaks and diagnostics.
nlohmann::json fit_json(const ident::AxisModes& m);
/// Help text: how to feed the files a Klipper printer writes.
std::string klipper_files_help();

}  // namespace tunekit::cli
