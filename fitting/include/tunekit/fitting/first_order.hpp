#pragma once
// First-order step-response models of the liquefier (Holtrup 2019 eq. 4.5-4.8):
//
//   y(t) = y0                                           for t <= t_step + theta
//   y(t) = y0 + K du (1 - exp(-(t - t_step - theta) / tau))  afterwards
//
// "fo" holds theta at 0 (first order), "fopdt" estimates it (first order plus dead time). A record
// that carries its logged input (StepRecord::u) is fitted as the response to that input instead.
// Single-step fits start from the log-incomplete-response method (Holtrup 2019 eq. 4.4), solve by
// Levenberg-Marquardt on the 4x4 normal equations (analytic Jacobian, one pass over the samples
// per trial) until Ceres Solver's convergence tests hold, with solve_least_squares taking over if
// they do not, and refuse (FitError) when tau cannot be seen in the record.

#include <span>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/fitting/least_squares.hpp"

namespace tunekit::fitting {

enum class StepModel { fo, fopdt };

/// Model name used in FitResult::model: "first_order" or "fopdt".
std::string model_name(StepModel m);

/// How a recorded input's samples stand for the input between them. `centred`: each value is
/// the input over a window centred on its time stamp, from half-way to the previous sample to
/// half-way to the next (a mean over the sample's window, as a printer's log of the feed
/// delivered around each force sample is; an input that changes between two samples changes
/// half-way, the same instant as StepInstant::midpoint). `from_stamp`: each value holds from its
/// stamp to the next (an input that changes exactly at sample instants).
enum class InputHold { centred, from_stamp };

/// The samples of one step: time (s), output, when the input changed and by how much.
/// Samples before t_step (the steady state before the step) determine y0 and theta.
///
/// Without `u` the input is an ideal step of du at t_step. With `u` (the recorded input, one value
/// per sample of t) the model is the first-order response to that input (held as `u_hold` says),
/// started settled at the mean input before t_step: a planner that pauses the feed for a few
/// milliseconds between moves, or ramps it over a few samples, is then in the model instead of
/// in the residuals (an ideal step reads the force's dip after a pause as a faster response).
/// y0 is the output at that settled start in both cases, K and tau_s mean the same.
///
/// With `input_t` and `input_u` (the commanded input on its own instants: a planner's moves,
/// set_input_track) the model is the first-order response to that input instead, started settled
/// at its value where the first sample's window begins: a stop between two moves then lies where
/// the planner put it, which the logged window means cannot say (each holds only the feed over
/// its whole window; a 5 ms window misplaces a stop's dip by up to 2.5 ms, a tenth of a 26 ms tau).
struct StepRecord {
  std::vector<double> t;          ///< s, increasing
  std::vector<double> y;          ///< output samples
  double t_step = 0;              ///< s, when the input changed
  double du = 1;                  ///< input change u_after - u_before (nonzero)
  std::string output_unit = "1";  ///< unit of y (and y0)
  std::string gain_unit = "1";    ///< unit of K (output unit per input unit)
  std::vector<double> u;          ///< the recorded input at t (input unit), or empty
  InputHold u_hold = InputHold::centred;
  /// The commanded input's breakpoints (s, non-decreasing, on the record's clock; two at one
  /// instant make a jump) and its values there (input unit), linear between them and held
  /// beyond; empty: the model follows `u` (or the ideal step).
  std::vector<double> input_t, input_u;
};

/// Whether a record's model follows an input (its commanded input track or its logged `u`)
/// rather than the ideal step.
bool follows_input(const StepRecord& r);

/// Gives a record the commanded input its model follows (StepRecord::input_t, input_u): the part
/// of the track (breakpoints t, values u as there) from where the first sample's window begins
/// to the last sample, its values at both ends interpolated. InputError unless t and u have the
/// same length (at least one), t does not decrease and both are finite.
void set_input_track(StepRecord& r, std::span<const double> t, std::span<const double> u);

/// Start values found by the log-incomplete-response method.
struct StepStart {
  double K = 0;
  double tau_s = 1;
  double theta_s = 0;
  double y0 = 0;
  double y_ss = 0;          ///< steady-state value assumed for the log transform
  double linearity_r2 = 0;  ///< R^2 of Z(t) = ln((y - y_ss)/(y0 - y_ss)) against t (0: method failed)
};

/// Holtrup 2019 eq. 4.4: Z = ln((y - y_ss) / (y0 - y_ss)) is a straight line of slope -1/tau that
/// crosses zero at t_step + theta. y_ss is unknown for a response that has not settled, so a few
/// candidates beyond the last samples are tried and the one that makes Z most linear is kept.
StepStart log_incomplete_start(const StepRecord& rec);

/// Whether a record's logged input is the ideal step over every sample window (a commanded
/// staircase logged at its levels): its driven model is then the ideal step's, which computes
/// several times faster, and the input can be left out. False for a record without an input.
bool logged_input_is_ideal_step(const StepRecord& r);

/// Model value at time t.
double step_response(double t, double t_step, double du, double K, double tau_s, double theta_s, double y0);

/// The model at every sample of a record, as the fits compute it: the ideal step's response, or
/// the response to the record's input when it has one (StepRecord::u). The output samples r.y are
/// not used.
std::vector<double> step_model_output(const StepRecord& r, double K, double tau_s, double theta_s, double y0);

/// Fits one step. Parameters: K (gain_unit), tau_s, theta_s (held at 0 for fo), y0 (output_unit).
/// Throws InputError for too few samples, a constant output or a zero step, and FitError when
/// the solver fails or tau / theta are not identifiable from the record. options: the
/// function and parameter tolerances are at least 1e-12 (relative; the start is polished close to
/// the optimum already), gradient_tolerance and max_iterations as given.
FitResult fit_step(const StepRecord& rec, StepModel model, const LsqOptions& options = {});

/// Fits several steps with one K, tau_s and theta_s and an own y0 per step (y0_0, y0_1, ...).
/// `start` (optional, may be null) gives K, tau_s, theta_s to start from. Solved with Ceres as
/// one residual block per step (the offsets eliminated by the Schur complement), from a start
/// polished on the normal equations; intervals from the (3 + steps)-square normal matrix, so the
/// cost grows with the samples only through the model evaluations.
FitResult fit_steps_pooled(const std::vector<StepRecord>& recs, StepModel model, const FitResult* start = nullptr,
                           const LsqOptions& options = {});

}  // namespace tunekit::fitting
