// tunekit resonance: axis resonances from accelerometer data: Welch PSD (and FRF when the
// commanded acceleration is known), peak detection, and a modal fit giving each mode's natural
// frequency and damping ratio with 95 % intervals. See docs/resonance.md.
#include <algorithm>
#include <memory>

#include <fmt/format.h>

#include "resonance_json.hpp"
#include "tunekit/calibration/analyses/resonance_command.hpp"

#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::calibration {

ResonanceOutcome compute_resonance(const ResonanceOptions& a) {
  ResonanceOutcome outcome;
  outcome.options = a;
  outcome.analysis = analyze_accel_files(a.accel, a.ringdown ? RingdownDiversion::all : RingdownDiversion::too_short);
  const auto& decays = outcome.analysis.ringdown_records;
  if (!decays.empty()) check_ringdown_options(a.ringdown_options);
  for (const auto& rec : decays) {
    auto rr = ident::analyze_ringdown(rec, a.ringdown_options);
    for (const auto& w : rec.warnings) outcome.warnings.push_back(w);
    for (const auto& w : rr.warnings) outcome.warnings.push_back(rec.path + ": " + w);
    const std::string label = record_label(rec.axis, rec.path);
    if (std::any_of(outcome.ringdowns.begin(), outcome.ringdowns.end(),
                    [&](const LabelledRingdown& r) { return r.label == label; }))
      throw InputError(fmt::format("two ring-down records under the label '{}'; analyse them one at a time", label),
                       rec.path);
    outcome.ringdowns.push_back({label, std::move(rr)});
  }
  return outcome;
}

Envelope to_envelope(const ResonanceOutcome& o) {
  Envelope env("resonance");
  env.set_options(accel_options_json(o.options.accel, o.options.ringdown, o.options.ringdown_options));
  add_accel_inputs(o.analysis, env);
  for (const auto& w : o.warnings) env.warn(w);
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  if (!o.ringdowns.empty()) {
    res["ringdown"] = nlohmann::json::object();
    for (const auto& r : o.ringdowns) res["ringdown"][r.label] = ident::to_json(r.result);
  }
  for (const auto& r : o.analysis.axes) {
    nlohmann::json j;
    j["modes"] = modes_json(r.modes);
    j["psd"] = spectrum_json(r.spectrum, o.options.accel.max_plot_hz);
    j["fit"] = fit_json(r.modes);
    if (r.modes.dominant >= 0) {
      const auto& d = r.modes.modes[static_cast<std::size_t>(r.modes.dominant)];
      j["freq_hz"] = d.freq_hz;  // the dominant mode, for --require x.freq_hz>=...
      j["zeta"] = d.zeta;
    }
    res["axes"][r.label] = j;
  }
  return env;
}

void print_text(const ResonanceOutcome& o, std::ostream& os) {
  for (const auto& lr : o.ringdowns) {
    const auto& r = lr.result;
    const std::string zeta = r.zeta_identified
                                 ? fmt::format("zeta = {:.4f} [{:.4f}, {:.4f}]", r.zeta, r.zeta_ci95_lo, r.zeta_ci95_hi)
                                 : fmt::format("zeta not identified (series {:.4f})", r.series_zeta);
    os << fmt::format("{}: ring-down in {} (strength {:.1f}): f = {:.2f} Hz [{:.2f}, {:.2f}]   {}{}\n", r.path,
                      r.channel, r.strength, r.freq_hz, r.freq_ci95_lo, r.freq_ci95_hi, zeta,
                      r.strongest_is_harmonic ? fmt::format(" (the strongest line, {:.2f} Hz, is its harmonic {})",
                                                            r.strongest_peak_hz, r.harmonic_number)
                                              : std::string());
  }
  for (const auto& r : o.analysis.axes) {
    const std::string how = r.modes.method.empty()             ? "no fit"
                            : r.modes.method == "output_error" ? "fitted to the record against its commanded motion"
                                                               : r.modes.method + " fit";
    os << fmt::format("{} {}: {} file(s), {} Welch segments of {} samples, {} modes ({})\n",
                      r.axis != 0 ? "axis" : "record", r.label, r.spectrum.files.size(), r.spectrum.segments,
                      r.spectrum.segment_length, r.modes.modes.size(), how);
    for (const auto& m : r.modes.modes)
      os << fmt::format("  f = {} Hz {}   zeta = {} {}\n", display_number(m.freq_hz),
                        display_interval(m.freq_ci95_lo, m.freq_ci95_hi), display_number(m.zeta),
                        display_interval(m.zeta_ci95_lo, m.zeta_ci95_hi));
  }
}

}  // namespace tunekit::calibration
