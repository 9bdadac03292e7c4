// The series behind the plots of tunekit calibrate's report (see calibrate_plotdata.hpp).
#include "tunekit/calibration/analyses/calibrate_plotdata.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "tunekit/calibration/analyses/whole_record.hpp"
#include "tunekit/fitting/first_order.hpp"
#include "tunekit/design/input_shaper.hpp"

namespace tunekit::calibration {

// A fitted parameter's value, NaN when the model has no such parameter (theta_s of a first-order fit).
double calibrate_param(const fitting::FitResult& f, const std::string& name) {
  for (const auto& p : f.params)
    if (p.name == name) return p.value;
  return std::nan("");
}

namespace {

// Each step's model over the samples its fit used and nowhere else (not over the warm-up from
// rest, which no step models), driven by the input the fit followed; NaN elsewhere.
std::vector<double> step_fits_output(const std::vector<double>& t, const std::vector<double>& u,
                                     const ident::StepAnalysis& steps) {
  std::vector<double> yf(t.size(), std::nan(""));
  for (const auto& s : steps.steps) {
    if (!s.fit) continue;
    const fitting::StepRecord r = ident::step_fit_record(steps, s.step, t, u, {});
    const auto& f = *s.fit;
    double theta = calibrate_param(f, "theta_s");
    if (!std::isfinite(theta)) theta = 0;
    const auto m = fitting::step_model_output(r, calibrate_param(f, "K"), calibrate_param(f, "tau_s"), theta,
                                              calibrate_param(f, "y0"));
    std::copy(m.begin(), m.end(), yf.begin() + static_cast<std::ptrdiff_t>(s.step.begin));
  }
  return yf;
}

// The whole-record model's legend text: its form and exponent.
std::string model_label(const ident::WholeRecordModel& m) {
  const auto& b = m.model.fit.param("b");
  if (b.fixed) return "whole-record model (linear)";
  return fmt::format("whole-record model (b = {:.2g})", b.value);
}

}  // namespace

// Series for the step plot: the measured record, each step's own fitted model and the whole-record model.
StepPlot step_plotdata(const StepOutcome& step, const std::string& u_label, const std::string& y_label) {
  // The record as compute_step() analysed it (the file is not read again).
  const auto& t = step.record.t;
  const auto& u = step.record.u;
  const auto& y = step.record.y;
  const std::vector<double> yf = step_fits_output(t, u, step.analysis);
  std::vector<double> ym;
  StepPlot d;
  d.u_label = u_label;
  d.y_label = y_label;
  if (const auto& m = step.whole_record.model) {
    ym = whole_record_output(*m, t, u);
    d.model_label = model_label(*m);
  } else {
    d.model_missing =
        step.whole_record.error.empty() ? std::string("the record has no input column") : step.whole_record.error;
  }
  // Thin very long records for the plot (every n-th sample).
  const std::size_t stride = std::max<std::size_t>(1, t.size() / 4000);
  for (std::size_t i = 0; i < t.size(); i += stride) {
    d.t_s.push_back(t[i]);
    d.u.push_back(u[i]);
    d.y.push_back(y[i]);
    d.y_fit.push_back(yf[i]);
    if (!ym.empty()) d.y_model.push_back(ym[i]);
  }
  return d;
}

BodePlot bode_plotdata(const FreqOutcome& chirp) {
  BodePlot d;
  const BodeCurve b = measured_bode(chirp);
  d.measured = {b.freq_hz, b.magnitude_db, b.phase_deg};
  if (chirp.broadband) d.coherence = chirp.broadband->coherence;
  // The model the summary reports: the fit freq names as its result.
  if (const auto m = reported_fit_bode(chirp))
    d.model = BodePlot::Model{{m->freq_hz, m->magnitude_db, m->phase_deg}, chirp.reported_fit_method()};
  return d;
}

PsdPlot psd_plotdata(const ShaperOutcome& shaper, const ShaperAxis& axis) {
  PsdPlot d;
  const ident::AxisSpectrum& s = axis.resonance.spectrum;
  for (std::size_t b = 0; b < s.freq_hz.size() && s.freq_hz[b] <= shaper.options.accel.max_plot_hz; ++b) {
    d.freq_hz.push_back(s.freq_hz[b]);
    d.psd.push_back(s.psd_sum[b]);
  }
  const auto& modes = axis.resonance.modes;
  for (const auto& m : modes.modes) d.mode_freq_hz.push_back(m.freq_hz);
  // Each candidate shaper's remaining vibration against frequency, at the identified damping.
  double zeta = 0.1;
  if (modes.dominant >= 0 && std::isfinite(modes.modes[static_cast<std::size_t>(modes.dominant)].zeta))
    zeta = modes.modes[static_cast<std::size_t>(modes.dominant)].zeta;
  d.recommended =
      PsdPlot::Recommended{design::to_string(axis.choice.recommended.type), axis.choice.recommended.freq_hz};
  for (const auto& c : axis.choice.candidates) {
    const auto shaper_design = design::design_shaper(c.type, c.freq_hz, c.damping_ratio,
                                                     design::kDefaultVibrationTolerance, design::EiDesign::damped_fit);
    d.shapers.push_back(
        {design::to_string(c.type), d.freq_hz, design::residual_vibration_curve(shaper_design, d.freq_hz, zeta)});
  }
  return d;
}

}  // namespace tunekit::calibration
