#pragma once
// The 95 % intervals an experiment is expected to give, before it runs: the Fisher information
// of its planned excitation. Each analysis fits a model by least squares to a record with white
// sensor noise of standard deviation sigma; linearised at the parameters p, its covariance is
// sigma^2 (J^T J)^-1 with J the model's sensitivities dy_i/dp_j at the samples (Ljung, System
// Identification: Theory for the User, 1999, section 9.3; the Cramer-Rao bound). J is computed
// here from the excitation as planned (the experiment as built and checked) and prior
// parameters, so the interval of each quantity is known before the machine moves:
//
//   liquefier record (flow sweep, chirp): the whole-record model of fitting/liquefier_model.hpp
//     (tau(q) = a q^b, dead time, a flow sensor's gain and offset, the stored volume at the
//     first sample) driven by the planned feed track (feed_track_plan.hpp), sampled at the
//     load cell's rate; quantities tau_ref_s (at the median feed), b, theta_s, g. The dead time
//     is told mostly by the first samples after each step's delayed kink, and where the load
//     cell's clock puts them is not known before the run: the covariance is the average over
//     sample grids of different phase and clock error (the expected variance);
//   axis sweep: one mode driven through its base (ident/base_excited_mode.hpp) by the sweep's
//     planned acceleration pulses, read by the accelerometer (y = a + g z'' + offset) at its
//     rate; quantities freq_hz and zeta. A fine pass is predicted from the mode its coarse pass
//     located (experiment_design.hpp), before it runs.
//
// The prediction holds for the fit's Wald interval when the model describes the record to its
// noise; an analysis that widens its intervals for correlated residuals reports wider ones.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/protocols/experiments.hpp"

namespace tunekit::protocols {

/// One quantity's predicted interval: value +- half_width (95 %), in the quantity's unit.
struct PredictedInterval {
  std::string quantity;  ///< "tau_ref_s", "b", "theta_s", "g", "freq_hz", "zeta"
  double value = 0;      ///< the prior value the prediction is made at
  double half_width = 0;
  double relative() const { return value != 0 ? half_width / std::abs(value) : 0.0; }
};

struct ExperimentPrediction {
  std::vector<PredictedInterval> intervals;
  std::string basis;  ///< the priors, in words
  const PredictedInterval* find(const std::string& quantity) const;
  nlohmann::json to_json() const;
};

/// The liquefier's prior: tau(u) = tau_ref_s (u / ref_feed_mm_s)^b (u a filament feed, mm/s),
/// the dead time, the force per mm/s of outflow (a flow sensor: y = gain q + offset) and the
/// load cell's noise (N rms) and sample rate (Hz).
struct LiquefierPrior {
  double tau_ref_s = 0.026, ref_feed_mm_s = 2.25, b = -0.5, theta_s = 0.02;
  double gain_N_per_mm_s = 3.5, offset_N = 0.5;
  double noise_N = 0.02, rate_hz = 200;
  std::string basis;
};

/// One axis mode's prior and the accelerometer's noise (mm/s^2 rms) and sample rate (Hz).
struct AxisPrior {
  double freq_hz = 45, zeta = 0.08;
  double noise_mm_s2 = 20, rate_hz = 3200;
  std::string basis;
};

/// What a calibration assumes before it has measured anything: a desktop printer with a
/// direct-drive extruder printing PLA. The advance 0.05 s, the low end of the typical 0.05-1 s of
/// Klipper's pressure-advance guide (O'Connor et al., Klipper documentation, Pressure_Advance.md),
/// is the stored melt over the flow, V(u) / u = tau(u) / (1 + b): with PLA's shear thinning
/// (power-law index about 0.5, b = n - 1 = -0.5) tau = 0.025 s at 2.25 mm/s of feed; the dead
/// time 0.02 s and the load cell's 3.5 N per mm/s are the built-in simulated desktop printer's
/// (docs/machine.md). The sensors' noise and rates are the caller's (the profile's sensors).
LiquefierPrior typical_liquefier_prior(double noise_N, double rate_hz);
/// A desktop printer's axis: 45 Hz, the middle of the 30-60 Hz a bed-slinger's and a CoreXY's
/// axes commonly show, and damping ratio 0.1, the one Klipper's input shaper assumes by default
/// (Klipper documentation, Measuring_Resonances.md, damping_ratio).
AxisPrior typical_axis_prior(double noise_mm_s2, double rate_hz);

/// The whole-record liquefier model's intervals from the experiment's planned feed track (a
/// load-cell experiment as build_experiment built it). InputError when it has no feed track.
ExperimentPrediction predict_liquefier_record(const Experiment& e, const LiquefierPrior& prior);

/// An axis-sweep's mode intervals from its planned pulses (build_experiment's parameters).
/// InputError for another protocol.
ExperimentPrediction predict_axis_sweep(const Experiment& e, const AxisPrior& prior);

}  // namespace tunekit::protocols
