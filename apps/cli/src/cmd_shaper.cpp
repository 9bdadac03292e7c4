// tunekit shaper: input shaper design and recommendation from accelerometer data. The default
// designs the shapers for the identified damping ratio and evaluates them over its 95 %
// interval; --klipper-compatible reproduces Klipper's published selection (assumed damping
// 0.1, vibrations pessimized over 0.075/0.1/0.15). See docs/resonance.md.
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "resonance_common.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/input_shaper.hpp"
#include "tunekit/ident/klipper_spectrum.hpp"
#include "tunekit/protocols/atomic_file.hpp"
#include "tunekit/protocols/firmware_limits.hpp"

namespace tunekit::cli {
namespace {

struct ShaperCliArgs {
  ResonanceCliArgs in;
  bool klipper = false;
  std::vector<std::string> shapers;
  double scv_mm_s = 5.0;
  double max_smoothing_mm = 0;
  double damping_ratio = -1;
  double max_shaper_freq_hz = -1;  ///< <0: Klipper's 150 Hz with --klipper-compatible, else 200 Hz
  double max_freq_hz = 200.0;
  std::string klipper_csv;
  std::string firmware;
};

// Klipper's calibrate_shaper.py stops its shaper frequencies below 150 Hz (MAX_SHAPER_FREQ in
// klippy/extras/shaper_calibrate.py); tunekit's own mode looks up to 200 Hz.
constexpr double kKlipperMaxShaperFreqHz = 150.0;
constexpr double kOwnMaxShaperFreqHz = 200.0;

// Klipper suggests max_accel rounded to 100 mm/s^2.
double klipper_suggested_accel(double a) { return std::round(a / 100.0) * 100.0; }

// A dataset's PSD as the shaper search sees it: Klipper-normalized.
ident::AxisSpectrum normalized_for_shaper(const ident::AxisSpectrum& s) {
  if (s.klipper_normalized) return s;
  ident::AxisSpectrum n = s;
  for (auto* p : {&n.psd_sum, &n.psd_x, &n.psd_y, &n.psd_z})
    if (!p->empty()) *p = ident::klipper_normalize(n.freq_hz, *p);
  n.klipper_normalized = true;
  return n;
}

std::string csv_path_for_axis(const std::string& pattern, const std::string& axis, std::size_t n_axes) {
  const auto pos = pattern.find("{axis}");
  if (pos == std::string::npos) {
    if (n_axes > 1)
      throw InputError("--klipper-csv needs '{axis}' in the file name when several axes are analysed, e.g. "
                       "calibration_data_{axis}.csv");
    return pattern;
  }
  return pattern.substr(0, pos) + axis + pattern.substr(pos + 6);
}

nlohmann::json candidate_json(const ident::ShaperCandidate& c) {
  return {{"type", ident::to_string(c.type)},
          {"freq_hz", c.freq_hz},
          {"damping", c.damping_ratio},
          {"vibrations_pct", 100.0 * c.vibrations},
          {"smoothing", c.smoothing_mm},
          {"max_accel_mm_s2", c.max_accel_mm_s2},
          {"suggested_max_accel_mm_s2", klipper_suggested_accel(c.max_accel_mm_s2)},
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
  const double max_shaper_freq =
      a.max_shaper_freq_hz > 0 ? a.max_shaper_freq_hz : (a.klipper ? kKlipperMaxShaperFreqHz : kOwnMaxShaperFreqHz);
  opts["max_shaper_freq_hz"] = max_shaper_freq;
  opts["max_freq_hz"] = a.max_freq_hz;
  opts["klipper_csv"] = a.klipper_csv;
  env.set_options(opts);
  if (!(a.max_freq_hz > 0)) throw InputError("--max-freq must be positive");
  if (!(max_shaper_freq > 0)) throw InputError("--max-shaper-freq must be positive");
  opts["firmware"] = a.firmware;
  std::optional<protocols::ExportFirmware> fw;
  if (!a.firmware.empty()) fw = protocols::parse_export_firmware(a.firmware);
  if (!(a.scv_mm_s >= 0)) throw InputError("--scv must not be negative");
  if (a.damping_ratio >= 1) throw InputError("--damping-ratio must be below 1");

  // Resolve the shaper list before reading data so that a typo fails fast.
  std::vector<ident::ShaperType> types;
  for (const auto& s : a.shapers) types.push_back(ident::parse_shaper_type(s));

  const auto axes = run_resonance_pipeline(a.in, env);
  if (!a.klipper_csv.empty()) (void)csv_path_for_axis(a.klipper_csv, "x", axes.size());  // fail before the search
  auto& res = env.results();
  res["axes"] = nlohmann::json::object();
  std::vector<std::pair<std::string, std::string>> csv_files;  // written once every axis succeeded
  for (const auto& r : axes) {
    const std::string& ax = r.label;
    ident::ShaperSelectionOptions so;
    so.scv_mm_s = a.scv_mm_s;
    so.max_smoothing_mm = a.max_smoothing_mm;
    so.max_shaper_freq_hz = max_shaper_freq;
    so.max_freq_hz = a.max_freq_hz;
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
    // The recommendation is made among the target firmware's shapers only, each within the
    // firmware's damping bound for it (firmware_limits.hpp).
    if (fw) {
      std::vector<ident::ShaperType> allowed;
      std::vector<std::string> dropped;
      for (const auto t : so.types) {
        const auto f = protocols::limits::find_shaper(*fw, ident::to_string(t));
        if (!f) continue;
        if (so.design_damping_ratio > f->max_damping) {
          dropped.push_back(fmt::format("{} (damping at most {})", f->firmware_name, f->max_damping));
          continue;
        }
        allowed.push_back(t);
      }
      if (allowed.empty())
        throw InputError(fmt::format("axis {}: none of the shapers considered is available in {} ({}) at the design "
                                     "damping {:.3f}",
                                     ax, protocols::limits::firmware_title(*fw), protocols::limits::shaper_list(*fw),
                                     so.design_damping_ratio));
      if (!dropped.empty())
        env.warn(fmt::format("axis {}: design damping {:.3f} is above {}'s bound for {}: not considered", ax,
                             so.design_damping_ratio, protocols::limits::firmware_title(*fw),
                             fmt::join(dropped, ", ")));
      so.types = allowed;
      sel["firmware"] = protocols::to_string(*fw);
    }
    // Klipper's selection works on its normalized PSD (divided by f + 0.1 Hz, damped below 10 Hz),
    // each recording (or dataset of a spectrum file) on its own; a shaper's vibrations are the
    // worst over them.
    std::vector<ident::AxisSpectrum> normalized;
    std::size_t applied = 0;
    for (const auto& d : r.datasets) {
      if (!d.klipper_normalized) ++applied;
      normalized.push_back(normalized_for_shaper(d));
    }
    std::vector<ident::PsdDataset> psds;
    for (const auto& d : normalized) psds.push_back({d.freq_hz, d.psd_sum});
    const auto choice = ident::select_shaper(psds, so);
    sel["psd_normalization"] =
        applied == normalized.size() ? "divided by (f + 0.1 Hz), damped below 10 Hz by tunekit (Klipper's normalization)"
        : applied == 0 ? "none applied: the spectrum file was already normalized by Klipper (it has shaper columns)"
                       : "Klipper's normalization (divided by (f + 0.1 Hz), damped below 10 Hz) applied by tunekit "
                         "to the measured spectra; the files with shaper columns were already normalized by Klipper";
    sel["datasets"] = normalized.size();
    sel["ei_design"] = "Singhose's damped fits";
    sel["max_freq_hz"] = so.max_freq_hz;
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

    if (!a.klipper_csv.empty()) {
      // Klipper's layout with the shaper response columns: the PSDs written are the normalized
      // ones (Klipper reads a file with shaper columns as already normalized).
      std::vector<ident::KlipperSpectrumColumn> cols;
      for (const auto& d : normalized) cols.push_back({d.files.empty() ? std::string("psd") : d.files.front(), &d});
      const auto grid = ident::klipper_spectrum_grid(cols, a.max_freq_hz);
      std::vector<ident::KlipperShaperColumn> shaper_cols;
      for (const auto& c : choice.candidates) {
        const auto sh = ident::design_shaper(c.type, c.freq_hz, c.damping_ratio, ident::kDefaultVibrationTolerance,
                                             so.ei_design);
        shaper_cols.push_back({ident::to_string(c.type), c.freq_hz,
                               ident::shaper_response(sh, grid, so.test_damping_ratios)});
      }
      const auto path = csv_path_for_axis(a.klipper_csv, ax, axes.size());
      csv_files.emplace_back(path, ident::write_klipper_spectrum(cols, shaper_cols, a.max_freq_hz));
      res["axes"][ax]["klipper_csv"] = path;
    }

    if (!a.in.output.json) {
      ctx.out << fmt::format("axis {}: ", ax);
      if (r.modes.modes.empty()) ctx.out << "no mode identified\n";
      else {
        ctx.out << "modes";
        for (const auto& m : r.modes.modes) ctx.out << fmt::format("  {:.1f} Hz (zeta {:.3f})", m.freq_hz, m.zeta);
        ctx.out << "\n";
      }
      for (const auto& c : choice.candidates) {
        // Klipper-compatible: max_accel as Klipper suggests it (rounded to 100 mm/s^2).
        const std::string accel = a.klipper ? fmt::format("suggested max_accel <= {:.0f} mm/s^2",
                                                          klipper_suggested_accel(c.max_accel_mm_s2))
                                            : fmt::format("max_accel {:.0f} mm/s^2", c.max_accel_mm_s2);
        ctx.out << fmt::format("  {:<9} {:6.1f} Hz  damping {:.3f}  vibrations {:5.1f} %  smoothing {:.3f} mm  {}\n",
                               ident::to_string(c.type), c.freq_hz, c.damping_ratio, 100 * c.vibrations,
                               c.smoothing_mm, accel);
      }
      const auto& b = choice.recommended;
      ctx.out << fmt::format("  recommended: shaper_type_{} = {}  shaper_freq_{} = {:.1f}  damping_ratio_{} = {:.3f}\n",
                             ax, ident::to_string(b.type), ax, b.freq_hz, ax, b.damping_ratio);
    }
  }
  for (const auto& [path, content] : csv_files) protocols::write_file_atomic(path, content);
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
  sub->add_option("--max-shaper-freq", args->max_shaper_freq_hz,
                  "Shaper frequencies tried stay below this, Hz (default 200; with --klipper-compatible 150, as Klipper)");
  sub->add_option("--max-freq", args->max_freq_hz,
                  "Highest PSD frequency the shapers are scored on, Hz (default 200; never below the highest shaper "
                  "frequency tried, as in Klipper's calibrate_shaper.py --max_freq)");
  sub->add_option("--klipper-csv", args->klipper_csv,
                  "Also write each axis's spectrum and shaper responses in Klipper's calibration_data layout "
                  "(freq,psd_x,psd_y,psd_z,psd_xyz,shapers:,...), readable by Klipper's calibrate_shaper.py; "
                  "'{axis}' in the name becomes x/y/z");
  sub->add_option("--firmware", args->firmware,
                  "Recommend among this firmware's shapers only (klipper, marlin or rrf), each within the firmware's "
                  "damping bound for it");
  sub->footer(klipper_files_help() +
              "\nExamples:\n"
              "  tunekit shaper /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv\n"
              "  tunekit shaper /tmp/raw_data_x_*.csv --klipper-compatible --json   # compare with calibrate_shaper.py\n"
              "  tunekit shaper /tmp/calibration_data_y_20240101.csv --max-smoothing 0.2\n"
              "  tunekit shaper /tmp/resonances_x_20240101.csv --klipper-compatible   # same as calibrate_shaper.py\n"
              "  tunekit shaper /tmp/raw_data_x_*.csv --klipper-csv calibration_data_{axis}.csv\n"
              "  tunekit shaper log.csv --axis x --accel ax --excitation ax_cmd --json -o shaper.json");
  sub->callback([args, &ctx] { set_exit_code(run_shaper(*args, ctx)); });
}

}  // namespace tunekit::cli
