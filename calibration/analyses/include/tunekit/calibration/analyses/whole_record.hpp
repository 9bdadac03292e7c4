#pragma once
// The whole-record liquefier model (ident/liquefier_record.hpp: one store of melt with
// tau(q) = a q^b, a continuous dead time and the sensor's gain and offset) as `tunekit step` and
// `tunekit freq` report it beside their per-step and per-frequency results: one fit, one terminal
// line, one JSON member `whole_record`, and the model's simulated output for the report's figure.

#include <limits>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/liquefier_record.hpp"
#include "tunekit/ident/step_analysis.hpp"
#include "tunekit/ident/whole_record_selection.hpp"

namespace tunekit::calibration {

using ident::WholeRecordResult;

/// The feed track for the log at `log`: `given` when not empty, else the feed_track.csv calibrate
/// writes beside each load-cell record when there is one (so that the single command on the
/// run's log reproduces calibrate's number), else none ("").
std::string feed_track_for(const std::string& given, const std::string& log);

/// The feed track file (none: nullptr) aligned with the record (t, u: time stamps and logged
/// window-mean feeds): ident::parse_feed_track_csv, then ident::align_feed_track on the whole record.
std::optional<ident::FeedTrackAlignment> aligned_feed_track(const InputFile* track, std::span<const double> t,
                                                            std::span<const double> u);

/// The terminal line: "  whole record: tau = a u^b, a = ..., b = ..., theta = ... s; <sensor>"
/// (with the step fits that disagree with it when it checked any), or
/// "  whole record: not fitted: <reason>"; nothing when it was not tried. With a finite
/// `u_compare` (freq: the record's mean input, the operating point its frequency response
/// linearises the liquefier at), also tau there with its 95 % interval (s).
void print_whole_record(std::ostream& os, const WholeRecordResult& r,
                        double u_compare = std::numeric_limits<double>::quiet_NaN());

/// results.whole_record: ident::to_json of the model (and its warnings added to the envelope), or
/// {error: reason}; nothing when it was not tried.
void add_whole_record(Envelope& env, const WholeRecordResult& r);

}  // namespace tunekit::calibration
