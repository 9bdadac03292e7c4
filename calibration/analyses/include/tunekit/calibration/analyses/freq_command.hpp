#pragma once
// tunekit freq as a function: the liquefier's frequency response (Holtrup, Tuning liquefier
// dynamics, MSc thesis, University of Twente, 2019, ch. 4.3.3 and appendices D-E) from a record
// of input (e.g. feed in mm/s) and output (force in N, line width in mm): a sine dwell at one
// known frequency, or a broadband H1 estimate with coherence, a transfer-function fit to it and
// an output-error refinement on the record. The shape of a command: docs/cpp-api.md.
//
// Without options beyond the file and its columns, the broadband analysis sizes itself from
// the record (tunekit/ident/excitation.hpp): it starts where the excitation leaves the steady
// hold before it, reports up to the top of the band the input excites, takes Welch segments
// that resolve that band, and fits the liquefier model, first order with dead time (Bellini,
// Guceri and Bertoldi, Liquefier dynamics in fused deposition, J. Manuf. Sci. Eng., 2004), by
// output error. `tunekit calibrate` analyses its chirp exactly so.
//
// Beside the per-frequency results, every mode fits the whole-record liquefier model
// (whole_record.hpp) to the record's commanded input and output: it needs no particular
// excitation. A record that cannot carry it (no input column, an input below zero, ...) is
// reported as not fitted with the reason and a warning; the command does not fail for it.

#include <complex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/whole_record.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/ident/excitation.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::calibration {

/// dwell: sine fit at a known frequency; h1: broadband H1 estimate; oe: h1, a TF fit, then the
/// output-error fit on the record; automatic: dwell when the frequency is given, else oe.
enum class FreqMode { automatic, dwell, h1, oe };

struct FreqOptions {
  std::string file;          ///< CSV log
  std::string time_column;   ///< empty: found by name
  std::string input_column;  ///< needed by h1 and oe; optional for a dwell
  std::string output_column;
  std::string input_unit, output_unit;  ///< override the units in the column names
  FreqMode mode = FreqMode::automatic;
  double freq_hz = 0;  ///< dwell: the excitation frequency (Hz)
  /// "P,Z": fit a transfer function with P poles and Z zeros. Empty: none for h1; for oe the
  /// liquefier model "1,0" with dead time (tf_delay is then implied).
  std::string fit_tf;
  bool tf_delay = false;  ///< with a dead time theta_s
  /// The output-error fit's input between samples (fitting::InterSample): automatic treats a
  /// staircase as centred on its time stamps (tunekit's recordings), a smooth input as band-limited.
  fitting::InterSample inter_sample = fitting::InterSample::automatic;
  /// Welch's method for h1/oe; segment_length 0: from the excited band (bins a sixteenth of its
  /// top apart), at least about 16 segments' worth of resolution, at most a quarter of the record.
  ident::WelchOptions welch;
  double fmin_hz = 0;  ///< lowest frequency reported and fitted (Hz)
  double fmax_hz = 0;  ///< highest (Hz); 0: the top of the band the input excites
  /// Broadband: the record before this time (s) is left out; unset: before the excitation's onset.
  std::optional<double> tmin_s;
  double min_coherence = 0.8;  ///< TF fit: points of lower coherence (0-1) are left out
  /// The whole-record model's intervals of b and theta by profile likelihood (slower) instead of
  /// Wald intervals widened for correlated residuals.
  bool profile_intervals = false;
  /// With input_column: the commanded feed on its own instants (ident/feed_track.hpp), which drives
  /// the whole-record model where it matches the logged window means. Empty: the logged feed.
  std::string feed_track;
};

/// The H1 estimate inside [fmin, fmax].
struct FreqBroadband {
  double start_s = 0;          ///< time of the first sample analysed (s)
  double fmax_hz = 0;          ///< the upper frequency used (Hz)
  ident::ExcitedBand excited;  ///< the band the input excites (Hz)
  double sample_rate_hz = 0;
  std::size_t segment_length = 0, segments = 0;
  std::vector<double> freq_hz;
  std::vector<std::complex<double>> h;  ///< output / input
  std::vector<double> coherence;
};

struct FreqOutcome {
  FreqOptions options;
  std::string time_column;
  std::string input_sha256;
  std::size_t input_size_bytes = 0;
  /// The feed track the whole-record model was driven by (options.feed_track, or the one found
  /// beside the log), as it was read; none without one.
  std::optional<InputDigest> feed_track_input;
  std::size_t samples = 0;
  std::string input_unit, output_unit;
  /// The input column's range and mean over the record (NaN without an input column); results
  /// "input_range".
  double input_min = fitting::kNaN, input_max = fitting::kNaN, input_mean = fitting::kNaN;
  std::optional<ident::SineDwell> dwell;     ///< mode dwell
  std::optional<FreqBroadband> broadband;    ///< modes h1 and oe
  std::optional<fitting::FitResult> tf_fit;  ///< --fit-tf: the fit to the frequency response
  std::size_t tf_points_used = 0;
  std::optional<fitting::FitResult> oe_fit;  ///< mode oe: the output-error fit to the record
  FreqMode mode = FreqMode::dwell;           ///< the mode run (automatic resolved)
  fitting::TfStructure structure;            ///< the fitted structure (fit_tf or the default)
  /// The whole-record liquefier model fitted to the record (from --tmin on when it is given; any
  /// mode, the input column needed), or why it could not be; results "whole_record".
  WholeRecordResult whole_record;
  std::vector<std::string> warnings;

  /// The transfer-function fit this analysis reports, results key "fit": the output-error fit
  /// when there is one (it uses every sample of the record, not only the coherent bins), else
  /// the fit to the H1 frequency response; nullptr when no model was fitted. Every reader of a
  /// frequency-response tau (report, history, export, batch) reads this one.
  const fitting::FitResult* reported_fit() const;
  /// "tf_oe_fit" or "tf_fit": the results key of the reported fit's full result.
  std::string reported_fit_key() const;
  /// How the reported fit was made, in words (results "fit.method").
  std::string reported_fit_method() const;
};

/// A frequency response as a Bode plot draws it: frequency (Hz), magnitude (output per input)
/// in plain ratio and in dB, phase in degrees unwrapped along frequency.
struct BodeCurve {
  std::vector<double> freq_hz, magnitude, magnitude_db, phase_deg;
};
/// The measured H1 response (results h1.bode); empty without a broadband analysis.
BodeCurve measured_bode(const FreqOutcome& outcome);
/// The reported fit's response at the measured frequencies (results <fit.source>.bode); nullopt
/// without a fitted model.
std::optional<BodeCurve> reported_fit_bode(const FreqOutcome& outcome);

/// InputError (exit 2) for bad input or options, FitError (exit 1) when a fit fails; located at
/// the file.
FreqOutcome compute_freq(const FreqOptions& options);

Envelope to_envelope(const FreqOutcome& outcome);
void print_text(const FreqOutcome& outcome, std::ostream& os);

std::string freq_mode_name(FreqMode mode);

}  // namespace tunekit::calibration
