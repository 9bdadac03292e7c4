#pragma once
// The liquefier identified from a whole record (fitting/liquefier_model.hpp: one store of melt
// with tau(q) = a q^b, a dead time and the sensor's gain and offset), beside the per-step fits of
// step_analysis.hpp, and the check of every step fit against the model: the model's own response
// over that step's window is fitted by the same first-order estimator, and a step whose tau
// differs from it by more than 1.96 combined standard errors (the step fit's and the model's tau
// at the step's arrival level) is flagged.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/fitting/liquefier_model.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::ident {

/// A pressure-like output (force N or kN, pressure Pa, kPa, MPa, bar) senses the stored volume,
/// anything else (a flow, a line width) the outflow.
fitting::LiquefierSensor sensor_for_output_unit(const std::string& unit);

/// One step fit held against the model's prediction for that step.
struct StepModelCheck {
  std::size_t step = 0;  ///< index into StepAnalysis::steps
  double u_after = fitting::kNaN;
  double tau_step_s = fitting::kNaN, tau_step_stderr_s = fitting::kNaN;
  double tau_model_s = fitting::kNaN, tau_model_stderr_s = fitting::kNaN;
  bool disagrees = false;
};

struct WholeRecordModel {
  fitting::LiquefierModelFit model;
  std::string input_unit = "1", output_unit = "1";
  double input_min_positive = fitting::kNaN, input_max = fitting::kNaN;  ///< the flows the record reached
  std::vector<StepModelCheck> checks;
  std::vector<std::string> warnings;
  /// tau at input q from the chosen model (s), and its standard error from the fit's covariance.
  double tau_at(double q) const;
  double tau_stderr_at(double q) const;
};

/// Fits the model to (t, u, y) and, when `steps` is given, checks its step fits against it.
WholeRecordModel analyze_whole_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                                      fitting::LiquefierSensor sensor, const std::string& input_unit,
                                      const std::string& output_unit, const StepAnalysis* steps);

/// {model (the fit), sensor, reference_input, a, b, theta_s (each {value, ci95, method}),
/// linear_chosen, test, variance_factor, substeps, input_range, step_checks, warnings}.
nlohmann::json to_json(const WholeRecordModel& m);

}  // namespace tunekit::ident
