#pragma once
// The command-line side of what `tunekit resonance`, `tunekit shaper` and `tunekit belts`
// share: binding the accelerometer and ring-down options straight into the library's option
// structs (the defaults --help shows are read from them), the help on feeding the files a
// printer writes, and the JSON of options, modes and spectra.

#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "tunekit/cli/context.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/resonance_common.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::cli {

/// Adds the files, input, spectrum and mode options, then the output options.
void add_accel_files_options(CLI::App* sub, AccelFilesOptions& o, OutputOptions& output);
/// Adds the ring-down options (--channel, --min-strength, band) and, when `ringdown_flag` is
/// given, --ringdown setting it.
void add_ringdown_options(CLI::App* sub, ident::RingdownOptions& o, bool* ringdown_flag);
/// InputError unless the ring-down options are usable (--min-strength positive).
void check_ringdown_options(const ident::RingdownOptions& o);
/// The options as the envelope records them (the ring-down ones included).
nlohmann::json accel_options_json(const AccelFilesOptions& a, bool ringdown, const ident::RingdownOptions& r);
/// The inputs (path, SHA-256, size) and the warnings of an analysis into the envelope.
void add_accel_inputs(const AccelAnalysis& analysis, Envelope& env);
/// modes[] as in the results contract.
nlohmann::json modes_json(const ident::AxisModes& m);
/// PSD (and FRF) arrays up to max_plot_hz for plotting.
nlohmann::json spectrum_json(const ident::AxisSpectrum& s, double max_plot_hz);
/// The fit's method, band, peaks and diagnostics.
nlohmann::json fit_json(const ident::AxisModes& m);
/// Help text: how to feed the files a Klipper or RepRapFirmware printer writes.
std::string klipper_files_help();

}  // namespace tunekit::cli
