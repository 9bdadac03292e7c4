#pragma once
// tunekit belts as a function: compare the two belts of a CoreXY machine from one pluck
// recording of each. Each belt's fundamental frequency in Hz (ring-down analysis with the
// fundamental chosen by its harmonic series over all three axes, tunekit/ident/ringdown.hpp),
// their difference and the tension ratio (fA / fB)^2; with the free span and the belt (options
// or the machine profile's [belts] section) each belt's tension in newtons from the taut-string
// model T = 4 mu L^2 f^2 (tunekit/ident/belt_tension.hpp) with a 95 % interval from the
// frequency's and the span's uncertainties, and which belt to tighten (or loosen), by roughly
// how much, to meet the target tension or, without one, to match the other belt. The shape of
// a command is described in docs/cpp-api.md.

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/resonance_common.hpp"
#include "tunekit/ident/belt_tension.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::calibration {

/// The ring-down settings for belts: printer belts ring at some 40-200 Hz, their second
/// harmonic stays below 400 Hz, and the band keeps out lines of the machine's electronics (an
/// ADXL345 channel can show one near 1.1 kHz); a fundamental damped more than zeta = 0.06 is a
/// tap or a bump of the frame, not a plucked belt. The other ring-down options are the library's.
ident::RingdownOptions belts_ringdown_defaults();

struct BeltsOptions {
  std::string file_a, file_b;  ///< accelerometer CSVs of one pluck each (#time,accel_x,accel_y,accel_z)
  /// Columns (time in s, accelerations in mm/s^2; empty: accel_x, accel_y, accel_z).
  ident::AccelInputOptions input;
  ident::RingdownOptions ringdown = belts_ringdown_defaults();  ///< band (Hz), channel, strength
  std::string profile;               ///< machine profile (TOML) whose [belts] section gives the values below
  std::string belt;                  ///< belt type, e.g. gt2-6mm (ident::belt_specs()); empty: the profile's
  double belt_mass_g_m = 0;          ///< the belt's linear mass, g/m; 0: the belt type's
  double span_mm = 0;                ///< free span plucked (between the contact points), mm; 0: the profile's
  double span_uncertainty_mm = 2.0;  ///< standard uncertainty of the span, mm (a rule's reading of
                                     ///< the contact points)
  double target_n = 0;               ///< tension to set, N; 0: the profile's, else match the belts
};

/// One belt's tension, when the span and the belt are known.
struct BeltTension {
  ident::StringTension tension;
  double target_hz = 0;  ///< the frequency at the target tension, Hz (0: no target)
};

struct BeltsOutcome {
  BeltsOptions options;             ///< as given, with the profile's values filled in
  std::vector<InputDigest> inputs;  ///< belt A's file, then belt B's (and the profile)
  ident::RingdownResult a, b;       ///< each belt's free decay
  double difference_hz = 0;         ///< fA - fB (damped frequencies), Hz
  double difference_stderr_hz = 0;
  double tension_ratio = 0;                          ///< (fA / fB)^2, dimensionless
  double tension_ratio_stderr = 0;                   ///< by the delta method
  double mass_kg_m = 0;                              ///< the belt's linear mass used, kg/m (0: no tensions)
  std::optional<BeltTension> tension_a, tension_b;   ///< N, when span and belt are known
  double difference_n = 0, difference_stderr_n = 0;  ///< TA - TB, N
  std::vector<std::string> advice;                   ///< what to do, one sentence per belt or pair
  std::vector<std::string> warnings;                 ///< "<file>: ..." from reading and fitting
};

/// Analyses both plucks. InputError (exit 2) for bad input, FitError (exit 1) for a record that
/// is no pluck (too weak, a tap, a steady tone) or a fit that failed.
BeltsOutcome compute_belts(const BeltsOptions& options);

/// The envelope: results a, b (the ring-downs), freq_a_hz, freq_b_hz, difference_hz with its
/// stderr and 95 % interval, tension_ratio with its stderr and 95 % interval; with a span and a
/// belt also belt (type, mass, span), tension_a_n and tension_b_n ({value, stderr, ci95}),
/// difference_n, target_n, and advice.
Envelope to_envelope(const BeltsOutcome& outcome);
void print_text(const BeltsOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
