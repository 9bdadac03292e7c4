#pragma once
// Which whole-record liquefier model a record carries (liquefier_record.hpp): the sensor, flow or
// pressure, chosen from the step fits' operating points or the output's unit, or by the record
// itself when the two sensors' models are compared by their residuals (equal parameter counts:
// the smaller AIC).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tunekit/ident/feed_track.hpp"
#include "tunekit/ident/liquefier_record.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::ident {

/// The model fitted to a record, or why it was not.
struct WholeRecordResult {
  std::optional<WholeRecordModel> model;
  std::string error;  ///< the plain reason it was not fitted; empty when it was (or was not tried)
};

/// Fits the model to a record: t (s, increasing), u the commanded input (a flow or feed, >= 0,
/// in `input_unit`), y the output (in `output_unit`). With `steps` (tunekit step) the sensor
/// (flow or pressure) is read from their operating points, else from the output's unit
/// (sensor_for_record), and the step fits are checked against the model. Without them
/// (tunekit freq), unless the unit's sensor gives the linear model (the same for either sensor),
/// the other sensor's model is fitted too and the one with the smaller residuals is kept (equal
/// parameter counts: the smaller AIC; a tie keeps the unit's), sensor_basis "residuals" when it
/// is not the unit's. Intervals of b and theta by profile likelihood when
/// `profile_intervals`, else widened Wald intervals.
/// A record that cannot carry the model is no failure: the result holds the reason, and
/// "whole-record model not fitted: <reason>" is added to `warnings`. With a `track` (the commanded
/// feed on its own instants, feed_track.hpp, aligned with the record) the model is driven by
/// it where it matches.
WholeRecordResult fit_whole_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                                   const std::string& input_unit, const std::string& output_unit,
                                   const StepAnalysis* steps, bool profile_intervals,
                                   std::vector<std::string>& warnings, const FeedTrackAlignment* track = nullptr);

}  // namespace tunekit::ident
