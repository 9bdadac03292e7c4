// tunekit shaper: input shaper design and recommendation from accelerometer data. The default
// designs the shapers for the identified damping ratio and evaluates them over its 95 %
// interval; --klipper-compatible reproduces Klipper's published selection (assumed damping
// 0.1, vibrations pessimized over 0.075/0.1/0.15). See docs/resonance.md.
#include <algorithm>
#include <memory>
#include <set>

#include <fmt/format.h>

#include "resonance_common.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/fitting/error.hpp"
#include "tunekit/ident/input_shaper.hpp"

namespace tunekit::cli {
namespace {

struct ShaperCliArgs {
  ResonanceCliArgs in;
  bool klipper = false;
  std::vector<std::string> shapers;
  double scv_mm_s = 5.0;
  double max_smoothing_mm = 0;
  double damping_ratio = -1;
  double max_shaper_freq_hz = 200.0;
};

nlohmann::json candidate_json(const ident::ShaperCandidate& c) {
  return {{"type", ident::to_string(c.type)},
          {"freq_hz", c.freq_hz},
          {"damping", c.damping_ratio},
          {"vibrations_pct", 100.0 * c.vibrations},
          {"smoothing", c.smoothing_mm},
          {"max_accel_mm_s2", c.max_accel_mm_s2},
          {"score", c.score}};
}

int run_shaper(const ShaperCliArgs& a, CliContext& ctx) {
  Envelope env("shaper");
  auto opts = resonance_options_json(a.in);
  opts["klipper_compatible"] = a.klipper;
  opts["shapers"] = a.shapers;
  opts["scv_mm_s"] = a.scv_mm_s;
  opts["max_smoothing_mm"] = a.max_smoothing_mm;
  opts["damping_ratio"] = a.damping_ratio;
  opts["max_shaper_freq_hz"] = a.max_shaper_freq_hz;
  env.set_options(opts);
  if (!(a.scv_mm_s >= 0)) throw InputError("--scv must not be negative");
  if (a.damping_ratio >= 1) throw InputError("--damping-ratio must be below 1");

  // Resolve the shaper list before reading data so that a typo fails fast.
  std::vector<ident::ShaperType> types;
  for (const auto& s : a.shapers) types.push_back(ident::parse_shaper_type(s));

  const auto axes = run_resonance_pipeline(a.in, env);
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  for (const auto& r : axes) {
    const std::string& ax = r.label;
    ident::ShaperSelectionOptions so;
    so.scv_mm_s = a.scv_mm_s;
    so.max_smoothing_mm = a.max_smoothing_mm;
    so.max_shaper_freq_hz = a.max_shaper_freq_hz;
    nlohmann::json sel;
    if (a.klipper || r.modes.modes.empty()) {
      if (!a.klipper)
        env.warn(fmt::format("axis {}: no mode was identified; shapers selected with Klipper's assumed damping", ax));
      if (!types.empty()) so.types = types;
      so.design_damping_ratio = a.damping_ratio > 0 ? a.damping_ratio : 0.1;
      so.test_damping_ratios = {0.075, 0.1, 0.15};
      sel["method"] = "klipper";
    } else {
      so.types = types.empty() ? std::vector<ident::ShaperType>{ident::ShaperType::zv, ident::ShaperType::mzv,
                                                                ident::ShaperType::zvd, ident::ShaperType::ei,
                                                                ident::ShaperType::zvdd, ident::ShaperType::two_hump_ei,
                                                                ident::ShaperType::three_hump_ei}
                               : types;
      const auto& dom = r.modes.modes[static_cast<std::size_t>(std::max(0, r.modes.dominant))];
      so.design_damping_ratio = a.damping_ratio > 0 ? a.damping_ratio : dom.zeta;
      std::set<double> tests;
      for (const auto& m : r.modes.modes)
        for (double z : {m.zeta_ci95_lo, m.zeta, m.zeta_ci95_hi})
          if (std::isfinite(z)) tests.insert(std::clamp(z, 0.001, 0.9));
      so.test_damping_ratios.assign(tests.begin(), tests.end());
      sel["method"] = "identified";
    }
    // Klipper's selection works on its normalized PSD (divided by f + 0.1 Hz, damped below 10 Hz).
    const auto psd = r.spectrum.klipper_normalized ? r.spectrum.psd_sum
                                                   : ident::klipper_normalize(r.spectrum.freq_hz, r.spectrum.psd_sum);
    const auto choice = ident::select_shaper(r.spectrum.freq_hz, psd, so);
    sel["design_damping"] = so.design_damping_ratio;
    sel["test_damping_ratios"] = so.test_damping_ratios;
    sel["score"] = "smoothing * (v^1.5 + 0.2 v + 0.01), v = remaining vibration fraction";
    sel["scv_mm_s"] = so.scv_mm_s;
    sel["freq_step_hz"] = so.freq_step_hz;
    sel["max_shaper_freq_hz"] = so.max_shaper_freq_hz;

    nlohmann::json j;
    j["modes"] = modes_json(r.modes);
    j["fit"] = fit_json(r.modes);
    j["recommended"] = candidate_json(choice.recommended);
    nlohmann::json cands = nlohmann::json::array();
    for (const auto& c : choice.candidates) cands.push_back(candidate_json(c));
    j["candidates"] = cands;
    j["selection"] = sel;
    j["psd"] = spectrum_json(r.spectrum, a.in.max_plot_hz);
    if (r.modes.dominant >= 0) {
      const auto& d = r.modes.modes[static_cast<std::size_t>(r.modes.dominant)];
      j["freq_hz"] = d.freq_hz;
      j["zeta"] = d.zeta;
    }
    res["axes"][ax] = j;

    if (!a.in.output.json) {
      ctx.out << fmt::format("axis {}: ", ax);
      if (r.modes.modes.empty()) ctx.out << "no mode identified\n";
      else {
        ctx.out << "modes";
        for (const auto& m : r.modes.modes) ctx.out << fmt::format("  {:.1f} Hz (zeta {:.3f})", m.freq_hz, m.zeta);
        ctx.out << "\n";
      }
      for (const auto& c : choice.candidates)
        ctx.out << fmt::format("  {:<9} {:6.1f} Hz  damping {:.3f}  vibrations {:5.1f} %  smoothing {:.3f} mm  "
                               "max_accel {:.0f} mm/s^2\n",
                               ident::to_string(c.type), c.freq_hz, c.damping_ratio, 100 * c.vibrations,
                               c.smoothing_mm, c.max_accel_mm_s2);
      const auto& b = choice.recommended;
      ctx.out << fmt::format("  recommended: shaper_type_{} = {}  shaper_freq_{} = {:.1f}  damping_ratio_{} = {:.3f}\n",
                             ax, ident::to_string(b.type), ax, b.freq_hz, ax, b.damping_ratio);
    }
  }
  return emit(env, a.in.output, ctx);
}

}  // namespace

void register_shaper(CLI::App& app, CliContext& ctx) {
  auto args = std::make_shared<ShaperCliArgs>();
  auto* sub = app.add_subcommand("shaper", "Input shaper design and recommendation from accelerometer data");
  add_resonance_options(sub, args->in);
  sub->add_flag("--klipper-compatible", args->klipper,
                "Select exactly as Klipper's calibrate_shaper.py does (assumed damping 0.1, vibrations pessimized "
                "over 0.075/0.1/0.15, Klipper's shaper list and tie-breaking) instead of using the identified damping");
  sub->add_option("--shapers", args->shapers,
                  "Shaper types to consider: zv mzv zvd zvdd ei 2hump_ei 3hump_ei (default: all; with "
                  "--klipper-compatible: zv mzv ei 2hump_ei 3hump_ei)");
  sub->add_option("--scv", args->scv_mm_s, "Square-corner velocity for smoothing, mm/s (default 5)");
  sub->add_option("--max-smoothing", args->max_smoothing_mm, "Largest acceptable smoothing, mm (default: no limit)");
  sub->add_option("--damping-ratio", args->damping_ratio,
                  "Design damping ratio (dimensionless; default: identified, or 0.1 with --klipper-compatible)");
  sub->add_option("--max-shaper-freq", args->max_shaper_freq_hz, "Highest shaper frequency tried, Hz (default 200)");
  sub->footer(klipper_files_help() +
              "\nExamples:\n"
              "  tunekit shaper /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv\n"
              "  tunekit shaper /tmp/raw_data_x_*.csv --klipper-compatible --json   # compare with calibrate_shaper.py\n"
              "  tunekit shaper /tmp/calibration_data_y_20240101.csv --max-smoothing 0.2\n"
              "  tunekit shaper log.csv --axis x --accel ax --excitation ax_cmd --json -o shaper.json");
  sub->callback([args, &ctx] { set_exit_code(run_shaper(*args, ctx)); });
}

}  // namespace tunekit::cli
