#pragma once
// The JSON of the accelerometer options and results `tunekit resonance`, `tunekit shaper` and
// `tunekit belts` share: options, inputs, modes, spectra and the modal fit.

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::calibration {

/// InputError unless the ring-down options are usable (--min-strength positive).
void check_ringdown_options(const ident::RingdownOptions& o);
/// The options as the envelope records them (the ring-down ones included).
nlohmann::json accel_options_json(const AccelFilesOptions& a, bool ringdown, const ident::RingdownOptions& r);
/// The inputs (path, SHA-256, size) and the warnings of an analysis into the envelope.
void add_accel_inputs(const AccelAnalysis& analysis, Envelope& env);
/// modes[] as in the results contract.
nlohmann::json modes_json(const ident::AxisModes& m);
/// The same for a list of mode estimates (the spectrum's fit beside an output-error fit).
nlohmann::json modes_json(const std::vector<fitting::ModeEstimate>& modes);
/// PSD (and FRF) arrays up to max_plot_hz for plotting.
nlohmann::json spectrum_json(const ident::AxisSpectrum& s, double max_plot_hz);
/// The fit's method, band, peaks and diagnostics.
nlohmann::json fit_json(const ident::AxisModes& m);

}  // namespace tunekit::calibration
