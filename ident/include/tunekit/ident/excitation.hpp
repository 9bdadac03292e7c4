#pragma once
// What the input of a record excites, read from the record itself: its holds (stretches at one
// level), where the excitation begins after the steady hold that precedes it, and the band of
// frequencies it puts power into. A frequency-response estimate is informative only where the
// input has power (Ljung, System identification: theory for the user, 2nd ed., 1999, ch. 13),
// and an output-error fit that starts the model at rest needs a record that starts at rest;
// `tunekit freq` sizes its broadband analysis from these when it is not told otherwise.

#include <cstddef>
#include <span>
#include <vector>

#include "tunekit/ident/spectrum.hpp"

namespace tunekit::ident {

/// Samples [first, last] over which the input stays at the level it had at `first`.
struct InputHold {
  std::size_t first = 0, last = 0;
};

/// The input's holds in order, covering every sample. A change smaller than a thousandth of the
/// input's range is no change of level.
std::vector<InputHold> input_holds(std::span<const double> u);

/// Time-weighted median duration (s) of the holds: half of the record's time lies in holds at
/// least this long. Seconds for a step test, a staircase step or one sample for a chirp.
double typical_hold_s(std::span<const double> t, std::span<const InputHold> holds);

/// Index of the sample at which the excitation begins: the last sample of the steady hold that
/// precedes it (the longest hold ending in the record's first half, when it is at least ten
/// times the typical hold). The system has then settled at that level, as a model started at
/// rest assumes. 0 when the record has no such hold.
std::size_t excitation_onset(std::span<const double> t, std::span<const double> u);

/// Frequencies (Hz) around the strongest non-zero bin of an input's power spectral density over
/// which it stays within 30 dB of that bin.
struct ExcitedBand {
  double lo_hz = 0, hi_hz = 0;
};
ExcitedBand excited_band(const Spectrum& input_psd);

}  // namespace tunekit::ident
