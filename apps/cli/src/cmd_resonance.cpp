// tunekit resonance: axis resonances from accelerometer data: Welch PSD (and FRF when the
// commanded acceleration is known), peak detection, and a modal fit giving each mode's natural
// frequency and damping ratio with 95 % intervals. See docs/resonance.md.
#include <memory>

#include <fmt/format.h>

#include "resonance_common.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"

namespace tunekit::cli {
namespace {

int run_resonance(const ResonanceCliArgs& a, CliContext& ctx) {
  Envelope env("resonance");
  env.set_options(resonance_options_json(a));
  const auto axes = run_resonance_pipeline(a, env);
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  for (const auto& r : axes) {
    const std::string ax(1, r.axis);
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
    for (const auto& r : axes) {
      ctx.out << fmt::format("axis {}: {} file(s), {} Welch segments of {} samples, {} modes ({} fit)\n", r.axis,
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
  sub->footer(klipper_files_help() +
              "\nExamples:\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv --json\n"
              "  tunekit resonance /tmp/calibration_data_x_20240101.csv\n"
              "  tunekit resonance log.csv --axis y --time t --accel ay --excitation ay_cmd --json -o y.json\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv --require 'x.freq_hz>=40'    # CI drift check");
  sub->callback([args, &ctx] { set_exit_code(run_resonance(*args, ctx)); });
}

}  // namespace tunekit::cli
