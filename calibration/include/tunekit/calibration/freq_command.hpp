#pragma once
// tunekit freq as a function: the liquefier's frequency response (Holtrup, Tuning liquefier
// dynamics, MSc thesis, University of Twente, 2019, ch. 4.3.3 and appendices D-E) from a record
// of input (e.g. feed in mm/s) and output (force in N, line width in mm): a sine dwell at one
// known frequency, or a broadband H1 estimate with coherence, a transfer-function fit to it and
// an output-error refinement on the record. The shape of a command: docs/cpp-api.md.

#include <complex>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/envelope.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/transfer_function.hpp"
#include "tunekit/ident/sine_dwell.hpp"
#include "tunekit/ident/spectrum.hpp"

namespace tunekit::calibration {

/// dwell: sine fit at a known frequency; h1: broadband H1 estimate; oe: h1, a TF fit, then the
/// output-error fit on the record.
enum class FreqMode { dwell, h1, oe };

struct FreqOptions {
  std::string file;          ///< CSV log
  std::string time_column;   ///< empty: found by name
  std::string input_column;  ///< needed by h1 and oe; optional for a dwell
  std::string output_column;
  std::string input_unit, output_unit;  ///< override the units in the column names
  FreqMode mode = FreqMode::dwell;
  double freq_hz = 0;     ///< dwell: the excitation frequency (Hz)
  std::string fit_tf;     ///< "P,Z": fit a transfer function with P poles and Z zeros
  bool tf_delay = false;  ///< with a dead time theta_s
  /// Welch's method for h1/oe; segment_length 0: a power of two giving about 16 segments.
  ident::WelchOptions welch;
  double fmin_hz = 0;          ///< lowest frequency reported and fitted (Hz)
  double fmax_hz = 0;          ///< highest (Hz); 0: Nyquist
  double tmin_s = 0;           ///< broadband: the record before this time (s) is left out
  double min_coherence = 0.8;  ///< TF fit: points of lower coherence (0-1) are left out
};

/// The H1 estimate inside [fmin, fmax].
struct FreqBroadband {
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
  std::size_t samples = 0;
  std::string input_unit, output_unit;
  std::optional<ident::SineDwell> dwell;     ///< mode dwell
  std::optional<FreqBroadband> broadband;    ///< modes h1 and oe
  std::optional<fitting::FitResult> tf_fit;  ///< --fit-tf: the fit to the frequency response
  std::size_t tf_points_used = 0;
  std::optional<fitting::FitResult> oe_fit;  ///< mode oe: the output-error fit to the record
  std::vector<std::string> warnings;
};

/// InputError (exit 2) for bad input or options, FitError (exit 1) when a fit fails; located at
/// the file.
FreqOutcome compute_freq(const FreqOptions& options);

Envelope to_envelope(const FreqOutcome& outcome);
void print_text(const FreqOutcome& outcome, std::ostream& os);

std::string freq_mode_name(FreqMode mode);

}  // namespace tunekit::calibration
