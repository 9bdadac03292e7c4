// tunekit resonance: axis resonances from accelerometer data: Welch PSD (and FRF when the
// commanded acceleration is known), peak detection, and a modal fit giving each mode's natural
// frequency and damping ratio with 95 % intervals. See docs/resonance.md.
#include <memory>

#include <fmt/format.h>

#include "resonance_common.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/ringdown.hpp"

namespace tunekit::cli {
namespace {

int run_resonance(const ResonanceCliArgs& a, CliContext& ctx) {
  Envelope env("resonance");
  env.set_options(resonance_options_json(a));
  std::vector<ident::AccelRecord> decays;
  const auto axes = run_resonance_pipeline(a, env, &decays);
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  std::vector<ident::RingdownResult> rings;
  if (!decays.empty()) {
    const auto ro = ringdown_options(a);
    res["ringdown"] = nlohmann::json::object();
    for (const auto& rec : decays) {
      auto rr = ident::analyze_ringdown(rec, ro);
      for (const auto& w : rec.warnings) env.warn(w);
      for (const auto& w : rr.warnings) env.warn(rec.path + ": " + w);
      const std::string label = record_label(rec.axis, rec.path);
      if (res["ringdown"].contains(label))
        throw InputError(fmt::format("two ring-down records under the label '{}'; analyse them one at a time", label),
                         rec.path);
      res["ringdown"][label] = ident::to_json(rr);
      rings.push_back(std::move(rr));
    }
  }
  for (const auto& r : axes) {
    const std::string& ax = r.label;
    nlohmann::json j;
    j["modes"] = modes_json(r.modes);
    j["psd"] = spectrum_json(r.spectrum, a.max_plot_hz);
    j["fit"] = fit_json(r.modes);
    if (r.modes.dominant >= 0) {
      const auto& d = r.modes.modes[static_cast<std::size_t>(r.modes.dominant)];
      j["freq_hz"] = d.freq_hz;  // the dominant mode, for --require x.freq_hz>=...
      j["zeta"] = d.zeta;
    }
    res["axes"][ax] = j;
  }
  if (!a.output.json) {
    for (const auto& r : rings)
      ctx.out << fmt::format("{}: ring-down in {} (strength {:.1f}): f = {:.2f} Hz [{:.2f}, {:.2f}]   zeta = {:.4f} "
                             "[{:.4f}, {:.4f}]{}\n",
                             r.path, r.channel, r.strength, r.freq_hz, r.freq_ci95_lo, r.freq_ci95_hi, r.zeta,
                             r.zeta_ci95_lo, r.zeta_ci95_hi,
                             r.strongest_is_harmonic
                                 ? fmt::format(" (the strongest line, {:.2f} Hz, is its harmonic {})",
                                               r.strongest_peak_hz, r.harmonic_number)
                                 : std::string());
    for (const auto& r : axes) {
      ctx.out << fmt::format("{} {}: {} file(s), {} Welch segments of {} samples, {} modes ({} fit)\n",
                             r.axis != 0 ? "axis" : "record", r.label,
                             r.spectrum.files.size(), r.spectrum.segments, r.spectrum.segment_length,
                             r.modes.modes.size(), r.modes.method.empty() ? "no" : r.modes.method);
      for (const auto& m : r.modes.modes)
        ctx.out << fmt::format("  f = {:.2f} Hz [{:.2f}, {:.2f}]   zeta = {:.4f} [{:.4f}, {:.4f}]\n", m.freq_hz,
                               m.freq_ci95_lo, m.freq_ci95_hi, m.zeta, m.zeta_ci95_lo, m.zeta_ci95_hi);
    }
  }
  return emit(env, a.output, ctx);
}

}  // namespace

void register_resonance(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<ResonanceCliArgs>();
  auto* sub = app.add_subcommand(
      "resonance", "Axis resonances from accelerometer data: PSD, modes with natural frequency and damping ratio");
  add_resonance_options(sub, *args);
  add_ringdown_options(sub, *args, true);
  sub->footer(klipper_files_help() +
              "\nExamples:\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv --json\n"
              "  tunekit resonance /tmp/calibration_data_x_20240101.csv\n"
              "  tunekit resonance log.csv --axis y --time t --accel ay --excitation ay_cmd --json -o y.json\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv --require 'x.freq_hz>=40'    # CI drift check\n"
              "  tunekit resonance --ringdown /tmp/adxl345-belt_A.csv   # a plucked belt: fundamental and damping\n"
              "Ring-down analysis: the fundamental and damping ratio of a free decay from a time-domain fit of damped\n"
              "sinusoids (matrix pencil start: Hua and Sarkar, IEEE Trans. ASSP, 1990; least-squares refinement).\n"
              "A record whose decay is below --min-strength times its noise floor is refused with exit 1.");
  sub->callback([args, &ctx] { set_exit_code(run_resonance(*args, ctx)); });
}

}  // namespace tunekit::cli
