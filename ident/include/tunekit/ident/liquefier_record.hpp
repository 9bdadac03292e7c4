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
#include "tunekit/ident/feed_track.hpp"
#include "tunekit/ident/rest_volume.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::ident {

/// A pressure-like output (force N or kN, pressure Pa, kPa, MPa, bar) senses the stored volume,
/// anything else (a flow, a line width) the outflow.
fitting::LiquefierSensor sensor_for_output_unit(const std::string& unit);

/// An output in a flow's unit (mm/s of filament feed, mm^3/s: a camera's delivered feed, a bead's
/// width times its speed) is the flow leaving the nozzle by what it is: its sensor is not for the
/// record to choose (a force or a pressure is the stored volume, or the flow where the melt's
/// force follows it, and the record decides).
bool output_is_flow(const std::string& unit);

/// What the output senses, read from the operating points when they show it: a sensor of the
/// stored volume (pressure, V = a q^(b+1)/(b+1)) has a step gain that follows tau, K(u) = g tau(u),
/// a sensor of the outflow a gain that does not depend on u. When tau's trend exponent is
/// significant (beyond 2 standard errors), the sensor whose prediction of K's trend exponent lies
/// fewer standard errors from the fitted one is chosen; otherwise (or without trends) `by_unit`.
/// `basis` (may be null) receives "unit" or "operating points".
fitting::LiquefierSensor sensor_for_record(const StepAnalysis& steps, fitting::LiquefierSensor by_unit,
                                           std::string* basis);

/// One step fit held against the model's prediction for that step.
struct StepModelCheck {
  std::size_t step = 0;  ///< index into StepAnalysis::steps
  double u_after = fitting::kNaN;
  double tau_step_s = fitting::kNaN, tau_step_stderr_s = fitting::kNaN;
  double tau_model_s = fitting::kNaN, tau_model_stderr_s = fitting::kNaN;
  bool disagrees = false;
};

/// The one rule for whether a record's step fits, taken together, contradict the whole-record
/// model: each check flags a step at a 5 % false-alarm rate (beyond 1.96 combined standard
/// errors), so the steps contradict the model when more of them disagree than that rate
/// explains, P(X >= disagreeing) < 1 % for X ~ Binomial(checks, 0.05). The step analysis warns by
/// it and the advance's design sets the model aside by it.
bool step_checks_contradict_model(std::size_t checks, std::size_t disagreeing);
/// How many of a model's step checks disagree with it.
std::size_t disagreeing_checks(const std::vector<StepModelCheck>& checks);
/// The rule above applied to a model's own step checks.
bool step_checks_contradict_model(const std::vector<StepModelCheck>& checks);

struct WholeRecordModel {
  fitting::LiquefierModelFit model;
  std::string input_unit = "1", output_unit = "1";
  double input_min_positive = fitting::kNaN, input_max = fitting::kNaN;  ///< the flows the record reached
  std::vector<StepModelCheck> checks;
  /// What chose the sensor: "unit", "operating points" or "residuals" (the record's own fits with
  /// either sensor, the smaller residuals kept; set by the caller).
  std::string sensor_basis = "unit";
  std::vector<std::string> warnings;
  /// The model was fitted from this sample on (the record before it is the settling from rest,
  /// below the flows the model describes), and driven by this input track (empty: the logged
  /// input); whole_record_output simulates it the same way.
  std::size_t first_sample = 0;
  FeedTrack input_track;
  /// The feed track's alignment with the record, when one was given.
  std::optional<FeedTrackAlignment> track_alignment;
  /// tau at input q from the chosen model (s), and its standard error from the fit's covariance.
  double tau_at(double q) const;
  double tau_stderr_at(double q) const;
  /// {var(ln tau_ref), cov(ln tau_ref, b), var(b)}, widened by the variance factor (b's terms 0
  /// when b is held): the delta method of any function of tau(q) needs only these.
  std::array<double, 3> ln_tau_ref_b_covariance() const;
  /// The widest relative 95 % half-width of tau over the flows the record reached (at their
  /// ends: the variance of log tau is quadratic in log q): what a design from the model's tau
  /// inherits from the fit. NaN when the range or the errors are unknown.
  double tau_relative_half_width_over_range() const;
  /// The stored volume at steady input q from the chosen model, V(q) = a q^(b+1) / (b+1) (input
  /// unit s), and its standard error from the fit's covariance (delta method in ln V).
  double volume_at(double q) const;
  double volume_stderr_at(double q) const;
  /// The widest relative 95 % half-width of V over the flows the record reached: with a pressure
  /// sensor V is what the sensor reads at every level, and a design from V(Q) inherits this.
  double volume_relative_half_width_over_range() const;
  /// The stored volume at the first level measured from the record's start-up transient
  /// (rest_volume.hpp), or the reason it was not.
  std::optional<RestVolume> rest_volume;
  std::string rest_volume_why;
};

/// Fits the model to (t, u, y) and, when `steps` is given, checks its step fits against it.
/// The intervals are Wald intervals widened for correlated residuals unless `options.profile`.
/// With `steps`, the fit starts at the first step's window: what comes before it is the liquefier
/// settling from rest, at flows below the sweep's, where a power law of the flow says nothing
/// (a melt's viscosity levels off at low shear; the stored volume at the start is a parameter).
/// With a `track` (feed_track.hpp, aligned with the record's window means by align_feed_track,
/// on the whole record: a part of it may not hold enough to place the track) the model is driven
/// by the commanded feed on its own instants instead of the means; a track that does not match
/// the record is not used, and a warning says so.
WholeRecordModel analyze_whole_record(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                                      fitting::LiquefierSensor sensor, const std::string& input_unit,
                                      const std::string& output_unit, const StepAnalysis* steps,
                                      const fitting::LiquefierFitOptions& options,
                                      const FeedTrackAlignment* track = nullptr);

/// The chosen model's output at the record's instants t (the ones it was fitted on), simulated as
/// it was fitted (from its first sample, with its track); NaN before the first sample.
std::vector<double> whole_record_output(const WholeRecordModel& m, const std::vector<double>& t,
                                        const std::vector<double>& u);

/// {model (the fit), sensor, reference_input, a, b, theta_s (each {value, ci95, method}),
/// linear_chosen, test, variance_factor, substeps, input_range, step_checks, warnings}.
nlohmann::json to_json(const WholeRecordModel& m);

}  // namespace tunekit::ident
