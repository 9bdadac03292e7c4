#pragma once
// The series behind the plots of `tunekit calibrate`'s report (plot_data.hpp; RUN_DIR/plotdata.json):
// the step records with each step's fitted model, the liquefier's Bode plot and each axis' PSD.

#include <string>

#include <nlohmann/json.hpp>
#include "tunekit/calibration/analyses/freq_command.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/calibration/results/plot_data.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/ident/step_analysis.hpp"

namespace tunekit::calibration {

/// A fitted parameter's value, NaN when the model has no such parameter (theta_s of a first-order fit).
double calibrate_param(const fitting::FitResult& f, const std::string& name);

/// The measured record (time s, input, output; thinned to about 4000 points), each step's own
/// fitted model over the samples its fit used (y_fit), and the whole-record model's simulated
/// output over all of it (y_model, with its legend text model_label) or, when it was not fitted,
/// why (model_missing).
/// The record is read again from the step analysis' file and columns (it needs an input column).
StepPlot step_plotdata(const StepOutcome& step, const std::string& u_label, const std::string& y_label);
/// Magnitude and phase of the measured frequency response and of the reported fitted model.
BodePlot bode_plotdata(const FreqOutcome& chirp);
/// One axis' PSD up to the plot's highest frequency, its fitted modes and each candidate
/// shaper's remaining vibration at the identified damping.
PsdPlot psd_plotdata(const ShaperOutcome& shaper, const ShaperAxis& axis);

}  // namespace tunekit::calibration
