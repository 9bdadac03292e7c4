// The series behind the plots of tunekit calibrate's report (see calibrate_plotdata.hpp).
#include "calibrate_plotdata.hpp"

#include <algorithm>
#include <cmath>

#include "tunekit/fitting/first_order.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/input_shaper.hpp"

namespace tunekit::calibration {

// A fitted parameter's value, NaN when the model has no such parameter (theta_s of a first-order fit).
double calibrate_param(const fitting::FitResult& f, const std::string& name) {
  for (const auto& p : f.params)
    if (p.name == name) return p.value;
  return std::nan("");
}

// Series for the step plot: the measured record and each step's own fitted model.
nlohmann::json step_plotdata(const std::string& csv, const ident::StepAnalysis& steps, const std::string& in_col,
                             const std::string& out_col, const std::string& u_label, const std::string& y_label) {
  const auto table = ident::read_csv(csv, {{"time", in_col, out_col}, "time"});
  const auto& t = table.column("time").values;
  const auto& u = table.column(in_col).values;
  const auto& y = table.column(out_col).values;
  // Each step's model is drawn over the samples its fit used and nowhere else (not over the
  // warm-up from rest, which no step models).
  std::vector<double> yf(t.size(), std::nan(""));
  for (const auto& s : steps.steps) {
    if (!s.fit) continue;
    const std::size_t begin = s.step.begin, end = std::min(s.step.end, t.size());
    const double ts = s.step.t_step_s;
    const double du = s.step.u_after - s.step.u_before;
    const auto& f = *s.fit;
    const double K = calibrate_param(f, "K"), tau = calibrate_param(f, "tau_s"), y0 = calibrate_param(f, "y0");
    double theta = calibrate_param(f, "theta_s");
    if (!std::isfinite(theta)) theta = 0;
    for (std::size_t i = begin; i < end; ++i) yf[i] = fitting::step_response(t[i], ts, du, K, tau, theta, y0);
  }
  // Thin very long records for the plot (every n-th sample).
  const std::size_t stride = std::max<std::size_t>(1, t.size() / 4000);
  nlohmann::json d{{"u_label", u_label}, {"y_label", y_label}};
  std::vector<double> ts, us, ys, fs_;
  for (std::size_t i = 0; i < t.size(); i += stride) {
    ts.push_back(t[i]);
    us.push_back(u[i]);
    ys.push_back(y[i]);
    fs_.push_back(yf[i]);
  }
  d["t_s"] = ts;
  d["u"] = us;
  d["y"] = ys;
  d["y_fit"] = fs_;
  return d;
}

nlohmann::json bode_plotdata(const FreqOutcome& chirp) {
  nlohmann::json d;
  const BodeCurve b = measured_bode(chirp);
  d["freq_hz"] = b.freq_hz;
  d["mag_db"] = b.magnitude_db;
  d["phase_deg"] = b.phase_deg;
  if (chirp.broadband) d["coherence"] = chirp.broadband->coherence;
  // The model the summary reports: the fit freq names as its result.
  if (const auto m = reported_fit_bode(chirp))
    d["model"] = {{"freq_hz", m->freq_hz},
                  {"mag_db", m->magnitude_db},
                  {"phase_deg", m->phase_deg},
                  {"label", chirp.reported_fit_method()}};
  return d;
}

nlohmann::json psd_plotdata(const ShaperOutcome& shaper, const ShaperAxis& axis) {
  nlohmann::json d;
  const ident::AxisSpectrum& s = axis.resonance.spectrum;
  std::vector<double> f, psd;
  for (std::size_t b = 0; b < s.freq_hz.size() && s.freq_hz[b] <= shaper.options.accel.max_plot_hz; ++b) {
    f.push_back(s.freq_hz[b]);
    psd.push_back(s.psd_sum[b]);
  }
  d["freq_hz"] = f;
  d["psd"] = psd;
  d["modes"] = nlohmann::json::array();
  const auto& modes = axis.resonance.modes;
  for (const auto& m : modes.modes) d["modes"].push_back({{"freq_hz", m.freq_hz}});
  // Each candidate shaper's remaining vibration against frequency, at the identified damping.
  double zeta = 0.1;
  if (modes.dominant >= 0 && std::isfinite(modes.modes[static_cast<std::size_t>(modes.dominant)].zeta))
    zeta = modes.modes[static_cast<std::size_t>(modes.dominant)].zeta;
  d["shapers"] = nlohmann::json::array();
  d["recommended"] = {{"type", ident::to_string(axis.choice.recommended.type)},
                      {"freq_hz", axis.choice.recommended.freq_hz}};
  for (const auto& c : axis.choice.candidates) {
    const auto shaper_design = ident::design_shaper(c.type, c.freq_hz, c.damping_ratio,
                                                    ident::kDefaultVibrationTolerance, ident::EiDesign::damped_fit);
    d["shapers"].push_back({{"type", ident::to_string(c.type)},
                            {"freq_hz", f},
                            {"response", ident::residual_vibration_curve(shaper_design, f, zeta)}});
  }
  return d;
}

}  // namespace tunekit::calibration
