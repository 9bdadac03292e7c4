// tunekit shaper's envelope and text summary (tunekit/calibration/shaper_command.hpp).
#include <cmath>

#include <fmt/format.h>

#include "resonance_json.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

namespace tunekit::calibration {
namespace {

// Klipper suggests max_accel rounded to 100 mm/s^2.
double shaper_klipper_suggested_accel(double a) { return std::round(a / 100.0) * 100.0; }

nlohmann::json shaper_candidate_json(const design::ShaperCandidate& c) {
  return {{"type", design::to_string(c.type)},
          {"freq_hz", c.freq_hz},
          {"damping", c.damping_ratio},
          {"vibrations_pct", 100.0 * c.vibrations},
          {"smoothing", c.smoothing_mm},
          {"max_accel_mm_s2", c.max_accel_mm_s2},
          {"suggested_max_accel_mm_s2", shaper_klipper_suggested_accel(c.max_accel_mm_s2)},
          {"score", c.score}};
}

nlohmann::json shaper_selection_json(const ShaperOutcome& o, const ShaperAxis& x) {
  const auto& so = x.selection;
  nlohmann::json sel;
  sel["method"] = x.klipper_method ? "klipper" : "identified";
  if (o.firmware) sel["firmware"] = firmware::to_string(*o.firmware);
  sel["firmware_assumed"] = o.firmware_assumed;
  sel["psd_normalization"] =
      x.normalized_by_us == x.datasets
          ? "divided by (f + 0.1 Hz), damped below 10 Hz by tunekit (Klipper's normalization)"
      : x.normalized_by_us == 0
          ? "none applied: the spectrum file was already normalized by Klipper (it has shaper columns)"
          : "Klipper's normalization (divided by (f + 0.1 Hz), damped below 10 Hz) applied by tunekit "
            "to the measured spectra; the files with shaper columns were already normalized by Klipper";
  sel["datasets"] = x.datasets;
  sel["ei_design"] = "Singhose's damped fits";
  sel["max_freq_hz"] = so.max_freq_hz;
  sel["design_damping"] = so.design_damping_ratio;
  sel["test_damping_ratios"] = so.test_damping_ratios;
  sel["score"] = "smoothing * (v^1.5 + 0.2 v + 0.01), v = remaining vibration fraction";
  sel["scv_mm_s"] = so.scv_mm_s;
  sel["freq_step_hz"] = so.freq_step_hz;
  sel["max_shaper_freq_hz"] = so.max_shaper_freq_hz;
  return sel;
}

// The recommendation in Klipper's (and Kalico's) configuration syntax where that firmware
// has the shaper; else in words that name no firmware's syntax, with the firmware's own name
// for the shaper when it differs ('tunekit export' writes it in that firmware's syntax).
void print_recommended(const ShaperOutcome& o, const std::string& ax, const design::ShaperCandidate& b,
                       std::ostream& os) {
  using firmware::ExportFirmware;
  const std::string type = design::to_string(b.type);
  const bool klipper_syntax = o.firmware == ExportFirmware::klipper || o.firmware == ExportFirmware::kalico;
  const auto in_firmware = o.firmware ? firmware::limits::find_shaper(*o.firmware, type) : std::nullopt;
  // The firmware's name of the shaper, empty when it lacks it (copied out of the optional: GCC's
  // -Wmaybe-uninitialized misreads the optional's pointer once inlined into fmt).
  const std::string fw_name = in_firmware ? std::string(in_firmware->firmware_name) : std::string();
  if (klipper_syntax && in_firmware) {
    os << fmt::format("  recommended: shaper_type_{} = {}  shaper_freq_{} = {:.1f}  damping_ratio_{} = {:.3f}\n", ax,
                      fw_name, ax, b.freq_hz, ax, b.damping_ratio);
    return;
  }
  const std::string own_name =
      in_firmware && type != fw_name
          ? fmt::format(" ({} calls it {})", firmware::limits::firmware_title(*o.firmware), fw_name)
          : std::string();
  os << fmt::format("  recommended: {} at {:.1f} Hz, damping ratio {:.3f}{}\n", type, b.freq_hz, b.damping_ratio,
                    own_name);
}

}  // namespace

Envelope to_envelope(const ShaperOutcome& o) {
  const ShaperOptions& a = o.options;
  Envelope env("shaper");
  auto opts = accel_options_json(a.accel, false, ident::RingdownOptions{});
  opts["klipper_compatible"] = a.klipper_compatible;
  nlohmann::json names = nlohmann::json::array();
  for (const auto t : a.shapers) names.push_back(design::to_string(t));
  opts["shapers"] = names;
  opts["scv_mm_s"] = a.selection.scv_mm_s;
  opts["max_smoothing_mm"] = a.selection.max_smoothing_mm;
  opts["max_vibrations_pct"] =
      a.selection.max_vibrations ? nlohmann::json(*a.selection.max_vibrations * 100) : nlohmann::json(nullptr);
  opts["damping_ratio"] = a.damping_ratio;
  opts["max_shaper_freq_hz"] = o.max_shaper_freq_hz;
  opts["max_freq_hz"] = a.selection.max_freq_hz;
  opts["klipper_csv"] = a.klipper_csv;
  opts["accel_limit_mm_s2"] = a.accel_limit_mm_s2;
  env.set_options(opts);
  for (const auto& d : o.inputs) env.add_input_digest(d.path, d.sha256, d.size_bytes);
  for (const auto& w : o.warnings) env.warn(w);
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  for (const auto& x : o.axes) res["axes"][x.resonance.label] = shaper_axis_json(o, x);
  return env;
}

ProposedAccel proposed_max_accel(const ShaperOutcome& o, const ShaperAxis& x) {
  // The acceleration to use with it: the shaper's own maximum, never above the printer's limit.
  const double shaper_max = x.choice.recommended.max_accel_mm_s2, limit = o.options.accel_limit_mm_s2;
  const bool capped = limit > 0 && shaper_max > limit;
  return {capped ? limit : shaper_klipper_suggested_accel(shaper_max), capped};
}

nlohmann::json shaper_axis_json(const ShaperOutcome& o, const ShaperAxis& x) {
  const AxisResult& r = x.resonance;
  nlohmann::json j;
  j["modes"] = modes_json(r.modes);
  j["fit"] = fit_json(r.modes);
  j["recommended"] = shaper_candidate_json(x.choice.recommended);
  const double shaper_max = x.choice.recommended.max_accel_mm_s2, limit = o.options.accel_limit_mm_s2;
  const auto [proposed, capped] = proposed_max_accel(o, x);
  j["proposed_max_accel_mm_s2"] = proposed;
  if (limit > 0) j["accel_limit_mm_s2"] = limit;
  if (capped)
    j["proposed_max_accel_note"] = fmt::format(
        "the shaper's smoothing allows {:.0f} mm/s^2, above the printer's limit {:g} mm/s^2: the limit is proposed",
        shaper_max, limit);
  nlohmann::json cands = nlohmann::json::array();
  for (const auto& c : x.choice.candidates) cands.push_back(shaper_candidate_json(c));
  j["candidates"] = cands;
  j["selection"] = shaper_selection_json(o, x);
  j["psd"] = spectrum_json(r.spectrum, o.options.accel.max_plot_hz);
  if (r.modes.dominant >= 0) {
    const auto& d = r.modes.modes[static_cast<std::size_t>(r.modes.dominant)];
    j["freq_hz"] = d.freq_hz;
    j["zeta"] = d.zeta;
  }
  if (!x.klipper_csv.empty()) j["klipper_csv"] = x.klipper_csv;
  return j;
}

void print_text(const ShaperOutcome& o, std::ostream& os) {
  for (const auto& x : o.axes) {
    const std::string& ax = x.resonance.label;
    const auto& modes = x.resonance.modes.modes;
    os << fmt::format("axis {}: ", ax);
    if (modes.empty()) os << "no mode identified\n";
    else {
      os << "modes";
      // Each mode with its 95 % intervals, as `tunekit resonance` and calibrate print them.
      for (const auto& m : modes)
        os << fmt::format("  {} Hz {} (zeta {} {})", display_number(m.freq_hz),
                          display_interval(m.freq_ci95_lo, m.freq_ci95_hi), display_number(m.zeta),
                          display_interval(m.zeta_ci95_lo, m.zeta_ci95_hi));
      os << "\n";
    }
    for (const auto& c : x.choice.candidates) {
      // Klipper-compatible: max_accel as Klipper suggests it (rounded to 100 mm/s^2).
      const std::string accel =
          o.options.klipper_compatible
              ? fmt::format("suggested max_accel <= {:.0f} mm/s^2", shaper_klipper_suggested_accel(c.max_accel_mm_s2))
              : fmt::format("max_accel {:.0f} mm/s^2", c.max_accel_mm_s2);
      os << fmt::format("  {:<9} {:6.1f} Hz  damping {:.3f}  vibrations {:5.1f} %  smoothing {:.3f} mm  {}\n",
                        design::to_string(c.type), c.freq_hz, c.damping_ratio, 100 * c.vibrations, c.smoothing_mm,
                        accel);
    }
    print_recommended(o, ax, x.choice.recommended, os);
    const double limit = o.options.accel_limit_mm_s2;
    if (limit > 0 && x.choice.recommended.max_accel_mm_s2 > limit)
      os << fmt::format("  max acceleration: the printer's limit {:g} mm/s^2 (the shaper would allow {:.0f})\n", limit,
                        x.choice.recommended.max_accel_mm_s2);
  }
  if (o.firmware_assumed)
    os << "recommended among Klipper's shapers (assuming Klipper; --firmware marlin|rrf|kalico to choose)\n";
}

}  // namespace tunekit::calibration
