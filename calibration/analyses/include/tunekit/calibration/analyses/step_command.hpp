#pragma once
// tunekit step as a function: identify liquefier dynamics (K, tau in s, theta in s) from a
// step-response log (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente, 2019,
// ch. 4.4.2). The shape of a command is described in docs/cpp-api.md.

#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/whole_record.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::calibration {

struct StepOptions {
  std::string file;           ///< CSV log
  std::string time_column;    ///< empty: found by name (time, t, timestamp, time_s)
  std::string input_column;   ///< empty: no input channel; the steps are given by group or step_size
  std::string output_column;  ///< e.g. force in N, ooze length in mm
  std::string input_unit;     ///< overrides the unit in the input column's name
  std::string output_unit;    ///< overrides the unit in the output column's name
  std::string group_column;   ///< without an input: one step per value of this column
  double step_time_s = 0;     ///< without an input: when the step happened (s)
  double step_size = std::numeric_limits<double>::quiet_NaN();  ///< without an input: the input change
  /// Model, step detection and operating points; the units are filled in by compute_step().
  ident::StepAnalysisOptions analysis;
  /// The whole-record model's intervals of b and theta by profile likelihood (slower) instead of
  /// Wald intervals widened for correlated residuals.
  bool profile_intervals = false;
  /// With input_column: also draw the step figure of the calibration report here (.svg or .png):
  /// the record, the whole-record model over all of it, each step's fit over its step, residuals.
  std::string plot_out;
  /// With input_column: the commanded feed on its own instants (ident/feed_track.hpp; calibrate's
  /// runs write it as feed_track.csv), which drives the whole-record model instead of the logged
  /// window means where it matches them. Empty: the logged feed.
  std::string feed_track;
};

/// A record's samples: time (s), input and output, in the columns' units.
struct StepRecordSeries {
  std::vector<double> t, u, y;
};

struct StepOutcome {
  StepOptions options;
  std::string time_column;  ///< the time column used
  std::string input_sha256;
  std::size_t input_size_bytes = 0;
  /// The feed track the whole-record model was driven by (options.feed_track, or the one found
  /// beside the log), as it was read; none without one.
  std::optional<InputDigest> feed_track_input;
  /// The record as analysed (time s, input, output), for the step figure; empty without an input column.
  StepRecordSeries record;
  std::string input_unit, output_unit, gain_unit;  ///< as results report them ("1": dimensionless)
  ident::StepAnalysis analysis;
  /// The whole-record model (records with an input channel), or why it could not be fitted.
  WholeRecordResult whole_record;
  std::vector<std::string> warnings;  ///< the CSV reader's, then the analysis'
  /// What the analysis found and the whole-record model explains (results "notes"): that the
  /// steps' dynamics differ with the level, when the model, whose tau follows the flow, describes
  /// the record to its noise (white residuals, every step fit agreeing with it). Nothing in them
  /// is left for the user to act on.
  std::vector<std::string> notes;
};

/// Reads the log and fits every step, the pooled steps and each operating point (and draws the
/// figure options.plot_out names). InputError (exit 2) for bad input, FitError (exit 1) when no
/// fit converges; both located at the file.
StepOutcome compute_step(const StepOptions& options);
/// The same on files already read: `file` holds options.file's bytes, `feed_track` the feed
/// track's (nullptr: none; compute_step(options) reads options.feed_track or the one beside the log).
StepOutcome compute_step(const StepOptions& options, const InputFile& file, const InputFile* feed_track);

Envelope to_envelope(const StepOutcome& outcome);
void print_text(const StepOutcome& outcome, std::ostream& os);

/// "fo" or "fopdt" and "midpoint" or "first": the names the command line uses.
std::string step_model_option_name(fitting::StepModel model);
std::string step_instant_option_name(ident::StepInstant instant);

}  // namespace tunekit::calibration
