#pragma once
// The whole-record grey-box liquefier model: one store of melt volume V fed by the commanded flow
// after a dead time and emptied through the nozzle, whose time constant depends on the flow
// (shear thinning; the gain scheduling of Holtrup, Tuning liquefier dynamics, MSc thesis,
// University of Twente, 2019, ch. 4.4.2, made one model):
//
//   dV/dt = u(t - theta) - q,    V(q) = a q^(b+1) / (b+1),   so tau(q) = dV/dq = a q^b,
//   sensor:  y = g q + c   (a flow sensor: camera, flow meter)
//        or  y = g V + c   (a pressure sensor: load cell, filament force; the melt pressure is
//                           proportional to the stored volume for a constant compliance).
//
// u and q are in the record's input unit (a flow, or a filament feed), a in s (input unit)^-b.
// b = 0 is the linear first-order model with tau = a. The dead time is continuous: the input
// (the record's commanded track when it carries one, else its samples) is interpolated linearly
// between its points and delayed by theta, never rounded to a sample.
//
// Simulation on the record's own time grid: between samples (and the delayed input's own
// breakpoints where its slope changes) the store is advanced by the exponential
// (Rosenbrock-)Euler step, the exact solution of the store linearised at the start of the step
// under a linearly varying input; it is exact for b = 0 and second-order accurate otherwise, with
// `substeps` equal sub-steps per piece sized from the smallest time constant the record reaches.
//
// Fit: output error over the whole record with Ceres, Jacobian by forward sensitivities: the
// derivatives of the state with respect to a, b, theta and V0 propagated beside it through every
// step (exact derivatives of the discrete model). The time constant is estimated at a
// reference input Q_ref (the median of the positive inputs) as tau_ref = a Q_ref^b, which nearly
// decorrelates it from b; a follows with its interval by the delta method. Start values: a grid
// of linear first-order models (tau, theta) on a thinned record, then the nonlinear model on the
// thinned record, then the whole record.
//
// Intervals: profile likelihood for b and theta (profile_likelihood.hpp), linearised (Wald) for
// tau_ref, g, c, V0 and a; a Wald interval ends at its parameter's domain (a dead time that ended
// at 0 is reported [0, hi], not +- around 0). Every interval is widened by the variance factor
// f = 1 + 2 sum_k rho_k of the residuals' autocorrelation (the sum over the lags up to the first
// non-positive rho_k; f >= 1, about 1 for white residuals): correlated residuals (a model that
// misses some dynamics, steps caught between samples) leave about n / f independent residuals,
// not n (Bayley and Hammersley, The "effective" number of independent observations in an
// autocorrelated time series, J. R. Stat. Soc. Suppl. 8, 1946).
//
// Choosing the linear model: b = 0 is kept when the profile-likelihood interval of b contains 0,
// which is the F-test of b = 0 at 5 % (S(0) - S_min <= s^2 f t^2, the same threshold).

#include <array>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::fitting {

/// What the record's output measures.
enum class LiquefierSensor {
  flow,     ///< y = g q + c
  pressure  ///< y = g V + c
};
std::string to_string(LiquefierSensor s);

/// A record: time (s, increasing), the commanded input (>= 0, a flow or feed) and the output.
struct LiquefierRecord {
  std::vector<double> t, u, y;
  /// The commanded input on its own instants, when the record carries it: the commanded feed is
  /// known exactly (from the G-code's moves), only the sensor is sampled. input_u (>= 0) at
  /// input_t (s, non-decreasing, on the record's clock), linear between them and held before the
  /// first and after the last; two points at the same instant make a step. Empty: the input is u
  /// at t, linear between the samples, so a step between two samples becomes a ramp across that
  /// interval (its instant is known to a sample interval only).
  std::vector<double> input_t, input_u;
  LiquefierSensor sensor = LiquefierSensor::flow;
  std::string input_unit = "1";
  std::string output_unit = "1";
};

struct LiquefierParams {
  double a = 1;  ///< s (input unit)^-b
  double b = 0;
  double theta_s = 0;
  double g = 1;      ///< output unit per input unit (flow sensor) or per input unit s (pressure)
  double c = 0;      ///< output unit
  double v0 = kNaN;  ///< stored volume at the first sample (input unit s); NaN: settled at the first input
};

/// The sensor output y = g s + c at every sample, s the outflow q (flow sensor) or the stored
/// volume V (pressure sensor). The store starts at p.v0 (NaN: settled at the first input).
/// substeps > 0: that many sub-steps in every piece; else sized per sample interval so that each
/// is at most liquefier_max_substep_s (1..64).
std::vector<double> simulate_liquefier(const std::vector<double>& t, const std::vector<double>& u,
                                       const LiquefierParams& p, LiquefierSensor sensor, int substeps = 0);

/// As above with the commanded input on its own instants (LiquefierRecord::input_t, input_u); the
/// output at the instants t.
std::vector<double> simulate_liquefier(const std::vector<double>& t, const std::vector<double>& input_t,
                                       const std::vector<double>& input_u, const LiquefierParams& p,
                                       LiquefierSensor sensor, int substeps = 0);

/// The derivatives of simulate_liquefier's output at every sample with respect to a, b, theta_s
/// and v0 (output unit per parameter unit; v0 must be given), the ones the fit's Jacobian is
/// made of.
std::vector<std::array<double, 4>> liquefier_sensitivities(const std::vector<double>& t, const std::vector<double>& u,
                                                           const LiquefierParams& p, LiquefierSensor sensor,
                                                           int substeps = 0);
/// The same with the commanded input on its own instants.
std::vector<std::array<double, 4>> liquefier_sensitivities(const std::vector<double>& t,
                                                           const std::vector<double>& input_t,
                                                           const std::vector<double>& input_u, const LiquefierParams& p,
                                                           LiquefierSensor sensor, int substeps = 0);

/// The longest sub-step (s): an eighth of the smallest time constant the input reaches under
/// (a, b); 0 when no input is positive.
double liquefier_max_substep_s(const std::vector<double>& u, double a, double b);

/// Sub-steps the longest sample interval needs so that each is at most liquefier_max_substep_s
/// (1..64).
int liquefier_substeps(const std::vector<double>& t, const std::vector<double>& u, double a, double b);

/// tau(q) = a q^b (s).
double liquefier_tau_s(const LiquefierParams& p, double q);
/// The stored volume at steady flow q, V(q) = a q^(b+1) / (b+1) (input unit s).
double liquefier_volume(const LiquefierParams& p, double q);

struct LiquefierFitOptions {
  double confidence = 0.95;
  bool profile = true;    ///< profile-likelihood intervals for b and theta (else Wald)
  bool fit_b = true;      ///< false: the linear model only
  double b_lower = -0.9;  ///< search bounds of b
  double b_upper = 1.0;
};

struct LiquefierModelFit {
  /// The chosen model: parameters tau_ref_s, b (fixed at 0 when the linear model is chosen),
  /// theta_s, g, c, V0 (the stored volume at the first sample: a record need not start
  /// settled, e.g. it starts with an empty liquefier); derived: a.
  FitResult fit;
  FitResult nonlinear;            ///< the fit with b free (== fit when it is chosen)
  double reference_input = kNaN;  ///< Q_ref, input unit
  LiquefierSensor sensor = LiquefierSensor::flow;
  bool linear_chosen = false;
  /// S(b=0) - S_min over s^2 f, against its 5 % threshold t^2 (the F statistic of b = 0).
  double f_statistic = kNaN, f_threshold = kNaN;
  double variance_factor = 1;  ///< f (about 1: residuals white)
  int substeps = 1;
  int profile_solves = 0;
  LiquefierParams params() const;  ///< the chosen model's values
};

/// Fits the model to a record. InputError for a record that cannot carry it (too short, time not
/// increasing, negative or constant input); FitError when no fit converges or a parameter is not
/// identifiable (the message says which and why).
LiquefierModelFit fit_liquefier_model(const LiquefierRecord& record, const LiquefierFitOptions& options = {});

}  // namespace tunekit::fitting
