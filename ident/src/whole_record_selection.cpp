// Which whole-record model a record carries (whole_record_selection.hpp).
#include "tunekit/ident/whole_record_selection.hpp"

#include <string_view>
#include <utility>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/liquefier_model.hpp"

namespace tunekit::ident {

namespace {

// The reason in plain words: the line and the warning already name the model.
std::string plain_reason(const Error& e) {
  constexpr std::string_view kPrefix = "whole-record model: ";
  std::string why = e.message();
  if (why.starts_with(kPrefix)) why.erase(0, kPrefix.size());
  return why;
}

fitting::LiquefierSensor other_sensor(fitting::LiquefierSensor s) {
  return s == fitting::LiquefierSensor::flow ? fitting::LiquefierSensor::pressure : fitting::LiquefierSensor::flow;
}

}  // namespace

WholeRecordResult fit_whole_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                                   const std::string& input_unit, const std::string& output_unit,
                                   const StepAnalysis* steps, bool profile_intervals,
                                   std::vector<std::string>& warnings, const FeedTrackAlignment* track) {
  WholeRecordResult r;
  fitting::LiquefierFitOptions fo;
  fo.profile = profile_intervals;
  std::string basis = "unit";
  const auto by_unit = sensor_for_output_unit(output_unit);
  bool refused = false;  // the record cannot carry the model (too short, an input below zero, ...)
  const bool flow_output = output_is_flow(output_unit);  // the sensor is not the record's to choose
  const auto sensor = steps != nullptr && !flow_output ? sensor_for_record(*steps, by_unit, &basis) : by_unit;
  try {
    r.model = analyze_whole_record(t, u, y, sensor, input_unit, output_unit, steps, fo, track);
  } catch (const Error& e) {
    r.error = plain_reason(e);
    refused = e.code() == ExitCode::bad_input;
  }
  if (!refused && !flow_output) {
    // The record decides: both sensors' models have the same parameters, and the one with the
    // smaller residuals (so the smaller AIC) is kept; a tie keeps the first choice (the operating
    // points', or the unit's). The operating points read the sensor from how K follows tau across
    // the levels, which ten times the simulated load cell's noise blurs: 14 of 200 such flow
    // sweeps chose the pressure sensor, whose model then took b = 0 and read tau 11-13 half-widths
    // off. The linear model is one model for either sensor (y = g a q + c or y = g q + c), but a
    // sensor may choose it only because its nonlinear model is the wrong one for the record (b's
    // interval then holds 0): the other sensor is fitted too.
    try {
      auto other = analyze_whole_record(t, u, y, other_sensor(sensor), input_unit, output_unit, steps, fo, track);
      if (!r.model || other.model.fit.diagnostics.rms < (1 - 1e-6) * r.model->model.fit.diagnostics.rms) {
        r.model = std::move(other);
        r.error.clear();
        basis = "residuals";
      }
    } catch (const Error&) {
      // The first choice's model (or its reason) stands.
    }
  }
  if (r.model) r.model->sensor_basis = basis;
  else warnings.push_back("whole-record model not fitted: " + r.error);
  return r;
}

}  // namespace tunekit::ident
