// tunekit shaper: input shaper design and recommendation from accelerometer data. The default
// designs the shapers for the identified damping ratio and evaluates them over its 95 %
// interval; --klipper-compatible reproduces Klipper's published selection (assumed damping
// 0.1, vibrations pessimized over 0.075/0.1/0.15). See docs/resonance.md. The envelope and the
// text are written by shaper_output.cpp.
#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <utility>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "resonance_json.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/klipper_spectrum.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/firmware/firmware_limits.hpp"

namespace tunekit::calibration {
namespace {

// The types considered with the identified damping, in the order the candidates are reported.
const std::vector<design::ShaperType>& shaper_identified_types() {
  static const std::vector<design::ShaperType> v = {design::ShaperType::zv,           design::ShaperType::mzv,
                                                    design::ShaperType::zvd,          design::ShaperType::ei,
                                                    design::ShaperType::zvdd,         design::ShaperType::two_hump_ei,
                                                    design::ShaperType::three_hump_ei};
  return v;
}

// A dataset's PSD as the shaper search sees it: Klipper-normalized.
ident::AxisSpectrum shaper_normalized_psd(const ident::AxisSpectrum& s) {
  if (s.klipper_normalized) return s;
  ident::AxisSpectrum n = s;
  for (auto* p : {&n.psd_sum, &n.psd_x, &n.psd_y, &n.psd_z})
    if (!p->empty()) *p = ident::klipper_normalize(n.freq_hz, *p);
  n.klipper_normalized = true;
  return n;
}

std::string shaper_csv_path_for_axis(const std::string& pattern, const std::string& axis, std::size_t n_axes) {
  const auto pos = pattern.find("{axis}");
  if (pos == std::string::npos) {
    if (n_axes > 1)
      throw InputError(
          "--klipper-csv needs '{axis}' in the file name when several axes are analysed, e.g. "
          "calibration_data_{axis}.csv");
    return pattern;
  }
  return pattern.substr(0, pos) + axis + pattern.substr(pos + 6);
}

// The types, design damping and test damping ratios for one axis.
void shaper_choose_damping(const ShaperOptions& a, const AxisResult& r, design::ShaperSelectionOptions& so,
                           ShaperAxis& out, std::vector<std::string>& warnings) {
  if (a.klipper_compatible || r.modes.modes.empty()) {
    if (!a.klipper_compatible)
      warnings.push_back(
          fmt::format("axis {}: no mode was identified; shapers selected with Klipper's assumed damping", r.label));
    if (!a.shapers.empty()) so.types = a.shapers;
    so.design_damping_ratio = a.damping_ratio > 0 ? a.damping_ratio : a.selection.design_damping_ratio;
    so.test_damping_ratios = a.selection.test_damping_ratios;
    out.klipper_method = true;
    return;
  }
  so.types = a.shapers.empty() ? shaper_identified_types() : a.shapers;
  const auto& dom = r.modes.modes[static_cast<std::size_t>(std::max(0, r.modes.dominant))];
  so.design_damping_ratio = a.damping_ratio > 0 ? a.damping_ratio : dom.zeta;
  std::set<double> tests;
  for (const auto& m : r.modes.modes)
    for (double z : {m.zeta_ci95_lo, m.zeta, m.zeta_ci95_hi})
      if (std::isfinite(z)) tests.insert(std::clamp(z, 0.001, 0.9));
  so.test_damping_ratios.assign(tests.begin(), tests.end());
}

// The recommendation is made among the target firmware's shapers only, each within the
// firmware's damping bound for it (firmware_limits.hpp).
void shaper_restrict_to_firmware(firmware::ExportFirmware fw, const std::string& ax, design::ShaperSelectionOptions& so,
                                 std::vector<std::string>& warnings) {
  std::vector<design::ShaperType> allowed;
  std::vector<std::string> dropped;
  for (const auto t : so.types) {
    const auto f = firmware::limits::find_shaper(fw, design::to_string(t));
    if (!f) continue;
    if (so.design_damping_ratio > f->max_damping) {
      dropped.push_back(fmt::format("{} (damping at most {})", f->firmware_name, f->max_damping));
      continue;
    }
    allowed.push_back(t);
  }
  if (allowed.empty())
    throw InputError(fmt::format(
        "axis {}: none of the shapers considered is available in {} ({}) at the design "
        "damping {:.3f}",
        ax, firmware::limits::firmware_title(fw), firmware::limits::shaper_list(fw), so.design_damping_ratio));
  if (!dropped.empty())
    warnings.push_back(fmt::format("axis {}: design damping {:.3f} is above {}'s bound for {}: not considered", ax,
                                   so.design_damping_ratio, firmware::limits::firmware_title(fw),
                                   fmt::join(dropped, ", ")));
  so.types = allowed;
}

// One axis's shaper selection: its options as run, the choice and the normalized datasets it
// was made on, with its warnings and its error kept for the caller to report in order (the
// selection may run beside the axis's mode fit, analyze_accel_files()).
struct AxisSelection {
  design::ShaperSelectionOptions options;
  ShaperAxis out;  // klipper_method, choice, datasets, normalized_by_us
  std::vector<ident::AxisSpectrum> normalized;
  std::vector<std::string> warnings;
  std::exception_ptr error;
};

AxisSelection shaper_select_axis(const ShaperOptions& a, double max_shaper_freq,
                                 std::optional<firmware::ExportFirmware> fw, const AxisResult& r) {
  AxisSelection s;
  try {
    s.options = a.selection;
    s.options.max_shaper_freq_hz = max_shaper_freq;
    shaper_choose_damping(a, r, s.options, s.out, s.warnings);
    if (fw) shaper_restrict_to_firmware(*fw, r.label, s.options, s.warnings);
    // Klipper's selection works on its normalized PSD (divided by f + 0.1 Hz, damped below 10
    // Hz), each recording (or dataset of a spectrum file) on its own; a shaper's vibrations are
    // the worst over them.
    for (const auto& d : r.datasets) {
      if (!d.klipper_normalized) ++s.out.normalized_by_us;
      s.normalized.push_back(shaper_normalized_psd(d));
    }
    s.out.datasets = s.normalized.size();
    std::vector<design::PsdDataset> psds;
    for (const auto& d : s.normalized) psds.push_back({d.freq_hz, d.psd_sum});
    s.out.choice = design::select_shaper(psds, s.options);
  } catch (...) {
    s.error = std::current_exception();
  }
  return s;
}

}  // namespace

const ShaperAxis* ShaperOutcome::axis(const std::string& label) const {
  for (const auto& a : axes)
    if (a.resonance.label == label) return &a;
  return nullptr;
}

ShaperOutcome compute_shaper(const ShaperOptions& a) {
  ShaperOutcome outcome;
  outcome.options = a;
  const double max_shaper_freq =
      a.max_shaper_freq_hz > 0 ? a.max_shaper_freq_hz
                               : (a.klipper_compatible ? kKlipperMaxShaperFreqHz : a.selection.max_shaper_freq_hz);
  outcome.max_shaper_freq_hz = max_shaper_freq;
  // Without --firmware the recommendation is printed in Klipper's syntax, so it is made among
  // Klipper's shapers (Klipper refuses any other at start-up, klippy/extras/shaper_defs.py).
  outcome.firmware_assumed = !a.firmware && a.shapers.empty();
  outcome.firmware = outcome.firmware_assumed ? std::optional(firmware::ExportFirmware::klipper) : a.firmware;
  if (!(a.selection.max_freq_hz > 0)) throw InputError("--max-freq must be positive");
  if (!(max_shaper_freq > 0)) throw InputError("--max-shaper-freq must be positive");
  if (!(a.selection.scv_mm_s >= 0)) throw InputError("--scv must not be negative");
  // calibrate_shaper.py refuses -v below 0.1 (per cent); NaN, infinities and an empty value too.
  const auto& mv = a.selection.max_vibrations;
  if (mv && !(*mv >= 0.001 && *mv <= 1)) throw InputError("--max-vibrations must be from 0.1 to 100 (per cent)");
  if (a.damping_ratio >= 1) throw InputError("--damping-ratio must be below 1");

  // With Klipper's method the selection does not use the modes: each axis's runs on another
  // core beside its mode fit; its warnings and errors are reported below, in the same order.
  std::map<std::string, AxisSelection> selected;
  std::mutex selected_mutex;
  BesideModes beside;
  if (a.klipper_compatible)
    beside = [&](const AxisResult& r) {
      AxisSelection s = shaper_select_axis(a, max_shaper_freq, outcome.firmware, r);
      const std::lock_guard lock(selected_mutex);
      selected.emplace(r.label, std::move(s));
    };
  AccelAnalysis analysis = analyze_accel_files(a.accel, RingdownDiversion::none, beside);
  outcome.inputs = std::move(analysis.inputs);
  outcome.warnings = std::move(analysis.warnings);
  const std::size_t n_axes = analysis.axes.size();
  if (!a.klipper_csv.empty()) (void)shaper_csv_path_for_axis(a.klipper_csv, "x", n_axes);  // fail before the search
  std::vector<std::pair<std::string, std::string>> csv_files;  // written once every axis succeeded
  for (auto& r : analysis.axes) {
    const auto done = selected.find(r.label);
    AxisSelection sel =
        done != selected.end() ? std::move(done->second) : shaper_select_axis(a, max_shaper_freq, outcome.firmware, r);
    outcome.warnings.insert(outcome.warnings.end(), sel.warnings.begin(), sel.warnings.end());
    if (sel.error) std::rethrow_exception(sel.error);
    ShaperAxis out = std::move(sel.out);
    design::ShaperSelectionOptions so = std::move(sel.options);
    const std::vector<ident::AxisSpectrum> normalized = std::move(sel.normalized);

    if (!a.klipper_csv.empty()) {
      // Klipper's layout with the shaper response columns: the PSDs written are the normalized
      // ones (Klipper reads a file with shaper columns as already normalized).
      std::vector<ident::KlipperSpectrumColumn> cols;
      for (const auto& d : normalized) cols.push_back({d.files.empty() ? std::string("psd") : d.files.front(), &d});
      const auto grid = ident::klipper_spectrum_grid(cols, so.max_freq_hz);
      std::vector<ident::KlipperShaperColumn> shaper_cols;
      for (const auto& c : out.choice.candidates) {
        const auto sh =
            design::design_shaper(c.type, c.freq_hz, c.damping_ratio, design::kDefaultVibrationTolerance, so.ei_design);
        shaper_cols.push_back(
            {design::to_string(c.type), c.freq_hz, design::shaper_response(sh, grid, so.test_damping_ratios)});
      }
      out.klipper_csv = shaper_csv_path_for_axis(a.klipper_csv, r.label, n_axes);
      csv_files.emplace_back(out.klipper_csv, ident::write_klipper_spectrum(cols, shaper_cols, so.max_freq_hz));
    }
    out.selection = std::move(so);
    out.resonance = std::move(r);
    outcome.axes.push_back(std::move(out));
  }
  for (const auto& [path, content] : csv_files) core::write_file_atomic(path, content);
  return outcome;
}

}  // namespace tunekit::calibration
