#pragma once
// tunekit resonance as a function: axis resonances from accelerometer data (Welch PSD, and the
// H1 frequency response when the commanded acceleration is known; peak detection; a modal fit
// giving each mode's natural frequency in Hz and damping ratio with 95 % intervals), and the
// fundamental and damping of free decays (ring-down: matrix pencil start, Hua and Sarkar, IEEE
// Trans. ASSP, 1990, then a least-squares fit of damped sinusoids). The shape of a command is
// described in docs/cpp-api.md.

#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::calibration {

struct ResonanceOptions {
  AccelFilesOptions accel;  ///< files, columns, Welch and mode options (the library's defaults)
  /// Analyse every generic CSV as a free decay; without it only records too short for Welch's
  /// method are.
  bool ringdown = false;
  ident::RingdownOptions ringdown_options;  ///< band (Hz), channel, strength threshold
};

/// A free decay and the label it is reported under (its axis letter or file stem).
struct LabelledRingdown {
  std::string label;
  ident::RingdownResult result;
};

struct ResonanceOutcome {
  ResonanceOptions options;
  /// Per axis: spectra and modes (analysis.axes), the files read and the pipeline's warnings.
  AccelAnalysis analysis;
  std::vector<LabelledRingdown> ringdowns;  ///< the records analysed as free decays, in file order
  std::vector<std::string> warnings;        ///< the ring-down analyses' (after analysis.warnings)
};

/// Reads the files and identifies each axis's modes and each free decay. InputError (exit 2)
/// for bad options or input (two ring-downs under one label), FitError (exit 1) when a fit
/// fails or a decay is too weak.
ResonanceOutcome compute_resonance(const ResonanceOptions& options);

/// The envelope: results.axes.<label> holds modes, psd, fit and the dominant mode's freq_hz and
/// zeta; results.ringdown.<label> each free decay.
Envelope to_envelope(const ResonanceOutcome& outcome);
void print_text(const ResonanceOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
