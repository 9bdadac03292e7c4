#pragma once
// What `tunekit export` designs the compensators from, as typed values: the liquefier's step
// response (tau, theta and K with their intervals, and the levels it was measured at), its
// frequency response (tau), each axis' recommended input shaper with every type's best
// candidate, and the rheology's prediction of tau over flow.
//
// They come from the analyses' typed outcomes (what `tunekit calibrate` hands over) or, at the
// boundary, from the results files a user names: read_design_inputs() has one reader per kind of
// result (step, freq, shaper, rheo) and is the only place export reads results JSON.

#include <array>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tunekit/calibration/results/agreement.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/ident/thermal_model.hpp"

namespace tunekit::calibration {

struct StepOutcome;
struct FreqOutcome;
struct ShaperOutcome;

/// A fitted value with its standard error and 95 % interval, in the value's unit (NaN: not given).
struct EstimatedValue {
  double value = fitting::kNaN;
  double std_error = fitting::kNaN;
  double ci95_lo = fitting::kNaN, ci95_hi = fitting::kNaN;
};

/// One operating point of a step analysis: the level the steps arrive at, u in the input's unit.
struct StepLevel {
  double u = fitting::kNaN;
  double K = fitting::kNaN, tau_s = fitting::kNaN, theta_s = fitting::kNaN;
  double tau_ci95_lo = fitting::kNaN, tau_ci95_hi = fitting::kNaN;  ///< s
  double flow_mm3_s = fitting::kNaN;  ///< the level as a volumetric flow when the record says it
};

/// The whole-record liquefier model of `tunekit step` (liquefier_record.hpp): tau = a u^b over
/// the input's unit, the dead time, and the inputs the record reached.
struct StepModelInput {
  EstimatedValue a, b, theta_s;
  bool linear = false;  ///< b held at 0 (the data do not support a flow-dependent tau)
  double u_min = fitting::kNaN, u_max = fitting::kNaN;
  /// tau's widest relative 95 % half-width over [u_min, u_max] (WholeRecordModel::
  /// tau_relative_half_width_over_range); NaN when unknown.
  double tau_rel_ci95 = fitting::kNaN;
  /// The sensor reads the stored volume at every level (a pressure sensor, y = g V + c): the
  /// model's V(Q) is measured, nothing below the data is extrapolated. volume_rel_ci95 is V's
  /// widest relative 95 % half-width over [u_min, u_max]; NaN when unknown.
  /// The model's reference input (input unit) and {var(ln tau_ref), cov(ln tau_ref, b), var(b)}
  /// (WholeRecordModel::ln_tau_ref_b_covariance): the delta method of V(Q). NaN when unknown.
  double u_ref = fitting::kNaN;
  std::array<double, 3> ln_tau_b_cov{fitting::kNaN, fitting::kNaN, fitting::kNaN};
  bool sensor_reads_volume = false;
  double volume_rel_ci95 = fitting::kNaN;
  /// The stored volume at the record's first level measured from its start-up transient (input
  /// unit s: mm of filament for a feed), with its 95 % interval (ident/rest_volume.hpp).
  struct RestVolume {
    double u = fitting::kNaN, value = fitting::kNaN, ci95_lo = fitting::kNaN, ci95_hi = fitting::kNaN;
  };
  std::optional<RestVolume> rest_volume;
};

/// From `tunekit step`: the pooled fit, the arrival levels (u > 0) and tau's trend over them.
struct StepDesignInput {
  std::string origin;  ///< the results file (or analysis) it came from, for messages
  EstimatedValue tau_s, theta_s, K;
  std::string K_unit;           ///< as the fit reports it; empty when unknown
  bool levels_in_flow = false;  ///< the levels' u is a volumetric flow (mm^3/s), not a feed (mm/s)
  std::vector<StepLevel> levels;
  std::optional<design::TauPowerLaw> trend;                                 ///< tau_s = a u^b over the levels
  double trend_b_ci95_lo = fitting::kNaN, trend_b_ci95_hi = fitting::kNaN;  ///< the trend's b, 95 %
  std::optional<StepModelInput> model;  ///< the whole-record model, when it was fitted
};

/// From `tunekit freq`: the frequency-response tau it reports (results.fit).
struct FreqDesignInput {
  std::string origin;
  EstimatedValue tau_s;
  /// The input the record swept (its unit the step test's, e.g. feed in mm/s): NaN without one.
  double input_min = fitting::kNaN, input_max = fitting::kNaN, input_mean = fitting::kNaN;
};

/// A shaper as `tunekit shaper` scored it (score: lower is better; NaN for the recommendation).
struct ScoredShaper {
  firmware::ShaperSetting setting;
  double score = fitting::kNaN;
};

/// From `tunekit shaper`, per axis ("x", "y").
struct AxisShaperInput {
  std::string origin;
  firmware::ShaperSetting recommended;
  std::vector<ScoredShaper> candidates;  ///< every type's best frequency
};

/// From `tunekit rheo` with a nozzle: tau(Q) / tau(Q_ref) at the given flows.
struct RheoDesignInput {
  std::string origin;
  std::vector<double> flow_mm3_s, relative_tau;
  double reference_flow_mm3_s = fitting::kNaN;
};

/// From `tunekit thermal`: the hot end's thermal model (results.thermal_model, one key per field of
/// ident::ThermalModel, each a number or a fitted parameter {value, stderr, ci95}).
struct ThermalDesignInput {
  std::string origin;
  ident::ThermalModel model;
};

struct DesignInputs {
  std::optional<StepDesignInput> step;
  std::optional<FreqDesignInput> freq;
  std::map<std::string, AxisShaperInput> axes;  ///< "x", "y"
  std::optional<RheoDesignInput> rheo;
  std::optional<ThermalDesignInput> thermal;
  std::vector<std::string> origins;       ///< every input in the order given (files: their paths)
  std::vector<InputDigest> files;         ///< files read: path, SHA-256 and size of the bytes read
  std::vector<std::string> warnings;      ///< inputs that cannot be exported (a z shaper, an unnamed axis)
  std::vector<std::string> unnamed_axes;  ///< of them, shapers of records that name no axis
};

/// The boundary: reads the results files a user names (the JSON of step, freq, shaper, rheo).
/// InputError (exit 2), located at the file, for a file that is not a tunekit results file or
/// holds something other than the numbers expected.
DesignInputs read_design_inputs(const std::vector<std::string>& results_files);

/// The same inputs from the analyses' typed outcomes; `origin` names them in messages.
StepDesignInput step_design_input(const StepOutcome& outcome, const std::string& origin);
FreqDesignInput freq_design_input(const FreqOutcome& outcome, const std::string& origin);

/// The step test's tau to hold against a frequency response: where the step test's operating
/// points show tau changing with the input (the trend's 95 % interval of b excludes 0) and the
/// frequency record's input range is known, the trend tau = a u^b at that record's mean input,
/// its interval the span the trend gives over the inputs the record swept (one tau fitted to a
/// flow-dependent liquefier's chirp may lie anywhere in it); otherwise the step fit's tau and
/// its 95 % interval. False when neither is finite. Calibrate and export both compare with it.
bool step_tau_for_freq(const StepDesignInput& step, const FreqDesignInput& freq, Estimate& out);
/// The axes of a shaper outcome (x and y; others are left out).
std::map<std::string, AxisShaperInput> shaper_design_inputs(const ShaperOutcome& outcome, const std::string& origin);

}  // namespace tunekit::calibration
