#pragma once
// The hot end's thermal model (thermal_model.hpp) identified from a whole thermal record
// (thermal_record.hpp): output error, the model's sensor temperature simulated from the
// record's heater duty, fan duty and feed and fitted to the measured temperature by the
// project's bounded least squares (fitting/least_squares.hpp), each parameter with its 95 %
// interval.
//
// The model's inputs are held over each sample interval (the duty a heater loop applies until
// its next tick; the fan's and the feed's means), over which the two linear equations are solved
// exactly. The record starts at rest: block and sensor at one temperature, a parameter of the
// fit. The heater's power P scales every other heat flow (C, A, F and H can be multiplied by a
// common factor without changing the temperatures), so it is not estimated: it is given, as
// Marlin's MPC_HEATER_POWER is, and C, A, F and H are relative to it. F is identified when the
// fan ran, H when filament was fed (otherwise each is held: F at A, H at 0, with a warning).
//
// Intervals: linearised (Wald, Student-t), widened by the variance factor of the residuals'
// autocorrelation (fitting/stats.hpp residual_variance_factor, as the liquefier's whole-record
// model does): correlated residuals leave fewer independent samples than there are samples.
// The residual checks: the Ljung-Box whiteness p-value, the variance factor, and the RMS.
//
// A held-out part (the samples from ThermalFitOptions::held_out_from_s after the start on) is not fitted: the
// model runs on through it from the fitted part's end, driven by the record's inputs, and its
// RMS error against the measured temperature is stated, with each held-out step's own RMS.

#include <optional>
#include <string>
#include <vector>

#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/thermal_model.hpp"
#include "tunekit/ident/thermal_record.hpp"

namespace tunekit::ident {

struct ThermalFitOptions {
  /// P: the heater's power at full duty, W (the cartridge's rating at the supply's voltage).
  double heater_power_w = 40.0;
  /// The samples from this long after the record's first sample on (s) are held out and
  /// predicted; NaN: the whole record is fitted.
  double held_out_from_s = fitting::kNaN;
  double confidence = 0.95;
};

/// A pair of parameters whose estimates are strongly correlated (|r| at or above 0.7).
struct ThermalCorrelation {
  std::string a, b;
  double r = 0;
};

/// One step of the held-out part (a run of samples with one fan duty and one feed, named by the
/// input that changed at its start) and the model's prediction error over it.
struct HeldOutStep {
  std::string input;  ///< "fan" or "feed"
  double from_s = 0, to_s = 0;
  double before = 0, after = 0;  ///< the input's value before and after (duty, or mm/s)
  double rms_c = 0;              ///< prediction's RMS error over the step, degC
  std::size_t samples = 0;
};

struct ThermalFit {
  /// The identified model (P as given).
  ThermalModel model;
  /// Parameters C_j_per_k, R_per_s, A_w_per_k, F_w_per_k, H_j_per_k_mm, ambient_c, start_c and
  /// their intervals; P_w fixed. Diagnostics: RMS, whiteness, convergence.
  fitting::FitResult fit;
  double variance_factor = 1;  ///< >= 1: the intervals' widening for correlated residuals
  std::vector<ThermalCorrelation> correlations;
  std::size_t fitted_samples = 0;
  /// The model's sensor temperature over the whole record (held-out part included), degC.
  std::vector<double> predicted_c;
  /// Held-out part: the RMS error of the prediction over it (NaN without one) and per step.
  double held_out_rms_c = fitting::kNaN;
  std::size_t held_out_samples = 0;
  std::vector<HeldOutStep> held_out_steps;
  std::vector<std::string> warnings;
};

/// Checks a record's shape (sizes, finite values, increasing time, duties in [0, 1], feed >= 0)
/// and throws InputError naming the first problem.
void check_thermal_record(const ThermalRecord& record);

/// The model's sensor temperature at each sample time, from block and sensor at `start_c`,
/// the inputs held over each interval.
std::vector<double> simulate_thermal_record(const ThermalModel& model, double start_c, const ThermalRecord& record);

/// Fits the model (see the header comment). InputError for a bad record or fewer than 20 fitted
/// samples, FitError when the fit does not converge or a parameter is not identifiable.
ThermalFit fit_thermal_record(const ThermalRecord& record, const ThermalFitOptions& options = {});

}  // namespace tunekit::ident
