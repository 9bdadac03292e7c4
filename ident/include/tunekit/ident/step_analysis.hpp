#pragma once
// Step-response analysis of the liquefier (Holtrup 2019 ch. 4.4.2, Table 4.3): find the steps in the
// input channel, fit each rising and falling step on its own (first order, optionally with dead
// time), pool all steps into one fit, tabulate K, tau, theta per operating point and fit a power
// law to them for gain scheduling (the liquefier is not linear time-invariant). A step's operating
// point is the level it arrives at (the state the liquefier settles in), the same in every command
// and in export; rising and falling arrivals are compared (flow_levels.cpp; the flow sweep of the
// liquefier-flow-sweep protocol reaches every level from both sides).

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/first_order.hpp"
#include "tunekit/ident/feed_track.hpp"

namespace tunekit::ident {

struct DetectedStep {
  std::size_t index = 0;   ///< 0-based order in the record
  std::size_t sample = 0;  ///< first sample at the new input level
  double t_step_s = 0;     ///< s, when the input changed (StepDetectOptions::instant)
  double u_before = 0, u_after = 0;
  std::size_t begin = 0, end = 0;  ///< samples [begin, end) used for this step's fit
  bool rising() const { return u_after > u_before; }
};

/// Where, between the last sample at the old input level and the first at the new one, the
/// input changed. A log that samples the input independently of when it changes (a printer's
/// or the simulator's log) puts the change anywhere in between: `midpoint` is unbiased there
/// (the time where the input crosses half-way, interpolated linearly; this also handles ramps
/// caught mid-way). A record whose input changes exactly at sample instants (a simulation
/// stepped at the sample times) is exact with `first_sample`. The choice moves t_step, and so
/// theta_s, by up to half a sample interval.
enum class StepInstant { midpoint, first_sample };

/// Default floor of a step, as a fraction of the input's range: half the smallest step of the
/// liquefier-flow-sweep protocol, so that every step of a sweep is found with a margin of two (its
/// lowest neighbouring levels differ by (r - 1) q_min with r = 10^(1/7) for its default 6 levels
/// over a decade, 4 % of the range).
inline constexpr double kDefaultMinStepFraction = 0.02;
/// A change of the input must also exceed this many standard deviations of the input's own
/// sample-to-sample noise (a measured input's scatter; a commanded one has none): at 8 sigma a
/// Gaussian excursion is called a step with a probability below 1e-15 per sample.
inline constexpr double kStepNoiseSigmas = 8;

struct StepDetectOptions {
  /// A change of the input is a step when it exceeds both this fraction of the input's range and
  /// kStepNoiseSigmas times the input's noise, and the input then holds a level (a change into a
  /// ramp is part of one transition, from the last level held to the next).
  double min_step_fraction = kDefaultMinStepFraction;
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

/// An operating point: the steps that ARRIVE at one input level (u_after: the state the
/// liquefier settles in), fitted together, with the difference between rising and falling
/// arrivals.
struct ArrivalLevel {
  double u = 0;  ///< input level (input unit), mean of its arrivals' u_after
  int n_rising = 0, n_falling = 0;
  std::vector<std::size_t> steps;  ///< indices into StepAnalysis::steps (successful fits only)
  fitting::FitResult fit;          ///< pooled over every arrival (a single step's fit for one)
  /// tau of the rising arrivals minus tau of the falling ones (s) with its 95 % interval
  /// (normal, from the two fits' standard errors); NaN unless both directions arrived.
  double rising_minus_falling_tau_s = fitting::kNaN;
  double rmf_ci95_lo = fitting::kNaN, rmf_ci95_hi = fitting::kNaN;
  bool directions_differ() const { return rmf_ci95_lo > 0 || rmf_ci95_hi < 0; }
};

/// Trends of the arrival levels with the input level: tau_s = a u^b and K = a u^b (fitted in
/// log space), theta_s = c0 + c1 u (a straight line: theta may be 0). Each with 95 % intervals
/// from three levels on. Fitted over the levels reached from both directions when at least
/// three are, else over every level.
struct LevelTrends {
  std::optional<fitting::FitResult> tau, K, theta;
  bool both_directions_only = false;
};

struct StepAnalysis {
  std::vector<StepFit> steps;
  std::optional<fitting::FitResult> pooled;  ///< empty (with a warning) when the pooled fit fails
  /// The operating points: steps grouped by the level they arrive at (flow_levels.cpp), sorted by u.
  std::vector<ArrivalLevel> arrival_levels;
  LevelTrends level_trends;      ///< the trends of the operating points with u
  std::string input_unit = "1";  ///< unit of u, as StepAnalysisOptions::input_unit
  /// How the step fits read the logged input between samples (from the step instant convention).
  fitting::InputHold input_hold = fitting::InputHold::centred;
  /// The commanded feed the step fits followed, on the record's clock (analyze_steps' track);
  /// empty: they followed the logged input.
  FeedTrack input_track;
  std::vector<std::string> warnings;
};

struct StepAnalysisOptions {
  fitting::StepModel model = fitting::StepModel::fopdt;
  StepDetectOptions detect;
  std::string output_unit = "1";
  std::string gain_unit = "1";
  std::string input_unit = "1";
};

/// Analysis of one record with an input channel. The steps are found in the logged input u; with
/// a `track` (the commanded input on the record's clock: FeedTrackAlignment::aligned of a track
/// that matches the record) every step fit follows it instead of the logged u (StepRecord::input_t),
/// which places a planner's stop between moves where it happened rather than anywhere in its
/// sample's window.
StepAnalysis analyze_steps(std::span<const double> t, std::span<const double> u, std::span<const double> y,
                           const StepAnalysisOptions& options = {}, const FeedTrack* track = nullptr);

/// The record a step of `a` was fitted on: samples [s.begin, s.end) of t and y (y may be empty:
/// the model's output alone is wanted), with the input its model follows, a.input_track when the
/// analysis had one, else the logged u held as a.input_hold.
fitting::StepRecord step_fit_record(const StepAnalysis& a, const DetectedStep& s, std::span<const double> t,
                                    std::span<const double> u, std::span<const double> y);

/// Analysis of records without an input channel (e.g. Holtrup 2019 Table B.1: ooze length after a
/// stop): each record is one step from u_before to u_after at `t_step`; its operating point is u_after.
struct KnownStep {
  fitting::StepRecord record;
  double u_before = 0, u_after = 1;
};
StepAnalysis analyze_known_steps(const std::vector<KnownStep>& steps, const StepAnalysisOptions& options = {});

/// Power law y = a x^b fitted in log space (x, y > 0). With two points the line is exact and
/// carries no uncertainty. `yname` names the quantity ("tau_s").
fitting::FitResult fit_power_law(std::span<const double> x, std::span<const double> y, const std::string& yname,
                                 const std::string& xunit, const std::string& yunit);

/// Groups the successful step fits by the level they arrive at (levels within 2 % of each
/// other are one), fits each group pooled and each direction on its own, fits the level
/// trends, and warns where a pooled fit's residuals are not white while its single-step fits
/// are (the steps do not share one K, tau, theta). `recs` are the steps' records, index for
/// index with a.steps. Fills a.arrival_levels, a.level_trends and a.warnings.
void analyze_arrival_levels(StepAnalysis& a, const std::vector<fitting::StepRecord>& recs,
                            const StepAnalysisOptions& options);

/// Ljung-Box p-value below which residuals count as not white in the pooled-fit warning.
inline constexpr double kWhitenessAlarmP = 1e-3;

/// The warning (empty when none) for a pooled fit over `members` single-step fits: its
/// residuals are not white (p < kWhitenessAlarmP) while at least three quarters of the
/// single-step fits' residuals are. `what` names the pooled fit ("pooled fit over all steps").
/// The words of the warnings that say the steps' dynamics differ with the level (the pooled fit
/// over all steps, and the rising and falling arrivals at one level).
inline constexpr const char* kDoNotShareDynamics = "do not share one K, tau and theta";
std::string pooled_whiteness_warning(const fitting::FitResult& pooled,
                                     const std::vector<const fitting::FitResult*>& members, const std::string& what);

/// JSON of the operating points (the arrival levels): [{u, unit, n_steps, n_rising, n_falling,
/// steps, tau_s, tau_ci95, K, K_ci95, theta_s, theta_ci95, stderr: {K, tau_s, theta_s},
/// rising_minus_falling_tau_s, rising_minus_falling_tau_ci95, directions_differ, fit}].
nlohmann::json arrival_levels_json(const StepAnalysis& a);
/// JSON of the level trends: {tau_s: {a, b, b_ci95, fit}, K: {a, b, b_ci95, fit},
/// theta_s: {c0, c1, c1_ci95, fit}, levels_used}.
nlohmann::json level_trends_json(const StepAnalysis& a);

/// JSON of a whole analysis: {steps[], steps_driven_by ("feed track" or "logged input"), pooled,
/// operating_points[] (arrival_levels_json), trend (level_trends_json)}.
nlohmann::json to_json(const StepAnalysis& a);

}  // namespace tunekit::ident
