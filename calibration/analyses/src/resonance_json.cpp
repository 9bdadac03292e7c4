// The JSON of the accelerometer options and results `tunekit resonance`, `tunekit shaper` and
// `tunekit belts` share (resonance_json.hpp).
#include "resonance_json.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"
#include "tunekit/fitting/fit_result.hpp"

namespace tunekit::calibration {
namespace {

std::vector<double> resonance_pair(double a, double b) { return {a, b}; }

}  // namespace

void check_ringdown_options(const ident::RingdownOptions& o) {
  if (!(o.min_strength > 0)) throw InputError("--min-strength must be positive");
}

nlohmann::json accel_options_json(const AccelFilesOptions& a, bool ringdown, const ident::RingdownOptions& r) {
  return {{"axis", a.input.axis != 0 ? std::string(1, a.input.axis) : std::string()},
          {"time_column", a.input.time_column},
          {"accel_columns", a.input.accel_columns},
          {"excitation_column", a.input.excitation_column},
          {"window", ident::to_string(a.welch.window)},
          {"kaiser_beta", a.welch.kaiser_beta},
          {"segment", a.welch.segment_length},
          {"overlap", a.welch.overlap},
          {"detrend", detrend_name(a.welch.detrend)},
          {"fit_min_hz", a.modes.fit_min_hz},
          {"fit_max_hz", a.modes.fit_max_hz},
          {"max_modes", a.modes.max_modes},
          {"peak_threshold", a.modes.peak_threshold},
          {"excitation_exponent", a.modes.excitation_exponent},
          {"full_scale_mm_s2", a.input.full_scale_mm_s2},
          {"no_frf", !a.modes.use_frf},
          {"no_commanded_motion", !a.modes.use_commanded_motion},
          {"ringdown", ringdown},
          {"channel", r.channel},
          {"min_strength", r.min_strength},
          {"ringdown_min_hz", r.min_hz},
          {"ringdown_max_hz", r.max_hz}};
}

void add_accel_inputs(const AccelAnalysis& analysis, Envelope& env) {
  for (const auto& d : analysis.inputs) env.add_input_digest(d.path, d.sha256, d.size_bytes);
  for (const auto& w : analysis.warnings) env.warn(w);
}

nlohmann::json modes_json(const ident::AxisModes& m) { return modes_json(m.modes); }

nlohmann::json modes_json(const std::vector<fitting::ModeEstimate>& modes) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& e : modes)
    arr.push_back({{"freq_hz", e.freq_hz},
                   {"zeta", e.zeta},
                   {"freq_ci95", resonance_pair(e.freq_ci95_lo, e.freq_ci95_hi)},
                   {"zeta_ci95", resonance_pair(e.zeta_ci95_lo, e.zeta_ci95_hi)},
                   {"freq_stderr_hz", e.freq_stderr_hz},
                   {"zeta_stderr", e.zeta_stderr},
                   {"gain", e.gain}});
  return arr;
}

nlohmann::json spectrum_json(const ident::AxisSpectrum& s, double max_hz) {
  nlohmann::json j;
  std::vector<double> f, p, px, py, pz;
  for (std::size_t b = 0; b < s.freq_hz.size(); ++b) {
    if (s.freq_hz[b] > max_hz) break;
    f.push_back(s.freq_hz[b]);
    p.push_back(s.psd_sum[b]);
    if (!s.psd_x.empty()) px.push_back(s.psd_x[b]);
    if (!s.psd_y.empty()) py.push_back(s.psd_y[b]);
    if (!s.psd_z.empty()) pz.push_back(s.psd_z[b]);
  }
  j["freq_hz"] = f;
  j["psd"] = p;
  if (!px.empty()) j["psd_x"] = px;
  if (!py.empty()) j["psd_y"] = py;
  if (!pz.empty()) j["psd_z"] = pz;
  j["unit"] = s.klipper_normalized ? "(mm/s^2)^2/Hz/Hz (Klipper-normalized)" : "(mm/s^2)^2/Hz";
  j["klipper_normalized"] = s.klipper_normalized;
  j["window"] = ident::to_string(s.welch.window);
  j["segment_length"] = s.segment_length;
  j["segments"] = s.segments;
  j["sample_rate_hz"] = s.sample_rate_hz;
  j["resolution_hz"] = s.segment_length > 0 ? s.sample_rate_hz / static_cast<double>(s.segment_length) : 0.0;
  j["files"] = s.files;
  if (s.frf && s.frf->h.size() >= f.size()) {
    std::vector<double> mag, ph, coh;
    for (std::size_t b = 0; b < f.size(); ++b) {
      mag.push_back(std::abs(s.frf->h[b]));
      ph.push_back(std::arg(s.frf->h[b]) * 180.0 / std::numbers::pi);
      coh.push_back(s.frf->coherence[b]);
    }
    j["frf"] = {{"freq_hz", f}, {"magnitude", mag}, {"phase_deg", ph}, {"coherence", coh}};
  }
  return j;
}

nlohmann::json fit_json(const ident::AxisModes& m) {
  nlohmann::json j;
  j["method"] = m.method.empty() ? "none" : m.method;
  j["band_hz"] = resonance_pair(m.band_lo_hz, m.band_hi_hz);
  nlohmann::json peaks = nlohmann::json::array();
  for (const auto& p : m.peaks) peaks.push_back({{"freq_hz", p.freq_hz}, {"half_power_zeta", p.half_power_zeta}});
  j["peaks"] = peaks;
  if (m.time_fit) {
    // The modes from the record against its commanded motion; the spectrum's fit started it.
    j["diagnostics"] = fitting::to_json(m.time_fit->diagnostics);
    j["variance_inflation"] = m.time_fit_variance_inflation;
    j["offset_mm_s2"] = m.time_fit->value("offset_mm_s2");
    if (m.fit)
      j["spectrum_fit"] = {{"method", "psd"},
                           {"modes", modes_json(m.fit->modes)},
                           {"diagnostics", fitting::to_json(m.fit->fit.diagnostics)},
                           {"variance_inflation", m.fit->variance_inflation}};
  } else if (m.fit) {
    j["diagnostics"] = fitting::to_json(m.fit->fit.diagnostics);
    j["variance_inflation"] = m.fit->variance_inflation;
    j["direct_term"] = m.fit->direct_term;
    if (m.method == "psd") j["noise_floor"] = m.fit->noise_floor;
  }
  j["dominant_mode"] = m.dominant;
  return j;
}

}  // namespace tunekit::calibration
