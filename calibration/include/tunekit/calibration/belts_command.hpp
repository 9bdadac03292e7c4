#pragma once
// tunekit belts as a function: compare the two belts of a CoreXY machine from one pluck
// recording of each, as the belt-comparison tools report it: each belt's fundamental frequency
// in Hz (ring-down analysis, tunekit/ident/ringdown.hpp), their difference, and the tension
// ratio (fA / fB)^2 (a string's tension is proportional to its frequency squared at equal length
// and mass per length). The shape of a command is described in docs/cpp-api.md.

#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/envelope.hpp"
#include "tunekit/calibration/resonance_common.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::calibration {

/// The ring-down band for belts: printer belts ring at some 40-200 Hz, their second harmonic
/// stays below 400 Hz, and the band keeps out lines of the machine's electronics (an ADXL345
/// channel can show one near 1.1 kHz). The other ring-down options are the library's.
ident::RingdownOptions belts_ringdown_defaults();

struct BeltsOptions {
  std::string file_a, file_b;  ///< accelerometer CSVs of one pluck each (#time,accel_x,accel_y,accel_z)
  /// Columns (time in s, accelerations in mm/s^2; empty: accel_x, accel_y, accel_z).
  ident::AccelInputOptions input;
  ident::RingdownOptions ringdown = belts_ringdown_defaults();  ///< band (Hz), channel, strength
};

struct BeltsOutcome {
  BeltsOptions options;
  std::vector<InputDigest> inputs;  ///< belt A's file, then belt B's
  ident::RingdownResult a, b;       ///< each belt's free decay
  double difference_hz = 0;         ///< fA - fB (damped frequencies), Hz
  double difference_stderr_hz = 0;
  double tension_ratio = 0;           ///< (fA / fB)^2, dimensionless
  double tension_ratio_stderr = 0;    ///< by the delta method
  std::vector<std::string> warnings;  ///< "<file>: ..." from reading and fitting
};

/// Analyses both plucks. InputError (exit 2) for bad input, FitError (exit 1) for a pluck too
/// weak or a fit that failed.
BeltsOutcome compute_belts(const BeltsOptions& options);

/// The envelope: results a, b (the ring-downs), freq_a_hz, freq_b_hz, difference_hz with its
/// stderr and 95 % interval, tension_ratio with its stderr and 95 % interval.
Envelope to_envelope(const BeltsOutcome& outcome);
void print_text(const BeltsOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
