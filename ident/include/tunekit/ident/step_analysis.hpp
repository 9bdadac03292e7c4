#pragma once
// Step-response analysis of the liquefier (Holtrup 2019 ch. 4.4.2, Table 4.3): find the steps in the
// input channel, fit each rising and falling step on its own (first order, optionally with dead
// time), pool all steps into one fit, tabulate K, tau, theta per operating point and fit a power
// law to them for gain scheduling (the liquefier is not linear time-invariant).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/first_order.hpp"

namespace tunekit::ident {

struct DetectedStep {
  std::size_t index = 0;       ///< 0-based order in the record
  std::size_t sample = 0;      ///< first sample at the new input level
  double t_step_s = 0;         ///< s, when the input changed (StepDetectOptions::instant)
  double u_before = 0, u_after = 0;
  std::size_t begin = 0, end = 0;  ///< samples [begin, end) used for this step's fit
  bool rising() const { return u_after > u_before; }
  /// The operating point of the step: the input level of larger magnitude (the running speed
  /// for a start or stop; the upper level for a step between two levels).
  double operating_point() const { return std::abs(u_before) >= std::abs(u_after) ? u_before : u_after; }
};

/// Where, between the last sample at the old input level and the first at the new one, the
/// input changed. A log that samples the input independently of when it changes (a printer's
/// or the simulator's log) puts the change anywhere in between: `midpoint` is unbiased there
/// (the time where the input crosses half-way, interpolated linearly; this also handles ramps
/// caught mid-way). A record whose input changes exactly at sample instants (a simulation
/// stepped at the sample times) is exact with `first_sample`. The choice moves t_step, and so
/// theta_s, by up to half a sample interval.
enum class StepInstant { midpoint, first_sample };

/// "midpoint" or "first"; InputError otherwise.
StepInstant parse_step_instant(const std::string& name);

struct StepDetectOptions {
  /// A change of the input by more than this fraction of its range is a step.
  double min_step_fraction = 0.1;
  /// Fraction of the preceding level's samples (before a step) included in that step's fit,
  /// the first level's included. analyze_steps() shortens this window further to the stretch
  /// where the output has settled (a warm-up from rest is not the steady state before a step).
  double pre_fraction = 0.5;
  StepInstant instant = StepInstant::midpoint;
};

/// Finds the steps of a (commanded, near piecewise-constant) input. Throws InputError when the
/// input is constant or no step leaves enough samples to fit.
std::vector<DetectedStep> detect_steps(std::span<const double> t, std::span<const double> u,
                                       const StepDetectOptions& options = {});

struct StepFit {
  DetectedStep step;
  std::optional<fitting::FitResult> fit;  ///< empty when the fit failed
  std::string error;                      ///< why, when it failed
};

struct OperatingPoint {
  double u = 0;
  int n_steps = 0;
  fitting::FitResult fit;  ///< pooled over the steps at this level
};

struct StepAnalysis {
  std::vector<StepFit> steps;
  std::optional<fitting::FitResult> pooled;  ///< empty (with a warning) when the pooled fit fails
  std::vector<OperatingPoint> operating_points;
  std::optional<fitting::FitResult> trend_tau;  ///< tau_s = a * u^b, with >= 2 operating points
  std::optional<fitting::FitResult> trend_K;    ///< K = a * u^b
  std::vector<std::string> warnings;
};

struct StepAnalysisOptions {
  fitting::StepModel model = fitting::StepModel::fopdt;
  StepDetectOptions detect;
  std::string output_unit = "1";
  std::string gain_unit = "1";
  std::string input_unit = "1";
};

/// Analysis of one record with an input channel.
StepAnalysis analyze_steps(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                           const StepAnalysisOptions& options = {});

/// Analysis of records without an input channel (e.g. Holtrup 2019 Table B.1: ooze length after a
/// stop): each record is one step of size `du` at `t_step`; its operating point is `du`.
struct KnownStep {
  fitting::StepRecord record;
  double u_before = 0, u_after = 1;
};
StepAnalysis analyze_known_steps(const std::vector<KnownStep>& steps, const StepAnalysisOptions& options = {});

/// Power law y = a x^b fitted in log space (x, y > 0). With two points the line is exact and
/// carries no uncertainty. `yname` names the quantity ("tau_s").
fitting::FitResult fit_power_law(std::span<const double> x, std::span<const double> y, const std::string& yname,
                                 const std::string& xunit, const std::string& yunit);

/// JSON of a whole analysis: {steps[], pooled, operating_points[], trend}.
nlohmann::json to_json(const StepAnalysis& a);

}  // namespace tunekit::ident
