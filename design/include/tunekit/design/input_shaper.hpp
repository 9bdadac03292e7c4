#pragma once
// Input shapers for a lightly damped mode, designed against a measurement (Singer & Seering 1990; Singhose, Seering &
// Singer 1994/1997; Singhose 2009 review): impulse sequences as functions of the design frequency and damping ratio,
// their residual vibration, the smoothing they add to a toolpath, the maximum acceleration that keeps that smoothing
// acceptable, and the automatic choice of a shaper against a measured vibration spectrum.
//
// Shaper names are spelled as Klipper spells them: "zv", "mzv", "zvd", "ei", "2hump_ei",
// "3hump_ei", plus "zvdd". Amplitudes are normalized to sum to 1, times start at 0 and are in
// seconds.
//
// Residual vibration (Singer-Seering): after the last impulse at T_n, the shaped response of a
// mode (natural frequency w, damping z, w_d = w sqrt(1 - z^2)) relative to the unshaped one is
//   V(w, z) = exp(-z w T_n) |sum_i A_i exp(z w T_i) exp(j w_d T_i)|.
//
// Smoothing (the path error a shaper adds; the measure Klipper publishes): with the shaper's
// centroid t_s = sum A_i T_i, at acceleration a and square-corner velocity v_sc,
//   s90  = sqrt(2) sum_{T_i >= t_s} A_i (v_sc + a/2 (T_i - t_s)) (T_i - t_s)
//   s180 = sum_i A_i a/2 (T_i - t_s)^2,   smoothing = max(s90, s180)   [mm].
// Both are linear in a, so the acceleration giving a target smoothing is solved exactly.

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "tunekit/design/shaper_defs.hpp"

namespace tunekit::design {

/// V(f, z): remaining vibration fraction of a mode at `freq_hz` with `damping_ratio`.
double residual_vibration(const Shaper& s, double freq_hz, double damping_ratio);
/// V over a frequency grid; uses a recurrence when the grid is uniform.
std::vector<double> residual_vibration_curve(const Shaper& s, std::span<const double> freq_hz, double damping_ratio);

/// Smoothing in mm at acceleration `accel_mm_s2` and square-corner velocity `scv_mm_s`.
double shaper_smoothing(const Shaper& s, double accel_mm_s2 = 5000.0, double scv_mm_s = 5.0);
/// Largest acceleration (mm/s^2) whose smoothing stays <= target_smoothing_mm (0 if none).
double shaper_max_accel(const Shaper& s, double scv_mm_s = 5.0, double target_smoothing_mm = 0.12);

/// One shaper evaluated against a spectrum.
struct ShaperCandidate {
  ShaperType type = ShaperType::zv;
  double freq_hz = 0;
  double damping_ratio = 0;  ///< the damping ratio the shaper is designed for (firmware setting)
  double vibrations = 0;     ///< remaining vibration fraction, worst over the test damping ratios
  double smoothing_mm = 0;   ///< at 5000 mm/s^2 and the square-corner velocity
  double max_accel_mm_s2 = 0;
  double score = 0;  ///< smoothing * (v^1.5 + 0.2 v + 0.01)
};

struct ShaperSelectionOptions {
  std::vector<ShaperType> types = {ShaperType::zv, ShaperType::mzv, ShaperType::ei, ShaperType::two_hump_ei,
                                   ShaperType::three_hump_ei};
  double design_damping_ratio = 0.1;                             ///< damping the shapers are designed for
  std::vector<double> test_damping_ratios = {0.075, 0.1, 0.15};  ///< vibrations are pessimized over these
  double scv_mm_s = 5.0;                                         ///< square-corner velocity
  double max_smoothing_mm = 0;                                   ///< 0: no limit
  /// Remaining vibrations the recommendation should stay under, as a fraction (0.01 = 1 %; none:
  /// no limit): Klipper's max_vibrations (calibrate_shaper.py -v, in per cent; Klipper 2026).
  std::optional<double> max_vibrations;
  /// PSD bins above max(max_freq_hz, highest shaper frequency tried) are ignored (Klipper's rule).
  double max_freq_hz = 200.0;
  double max_shaper_freq_hz = 200.0;          ///< shaper frequencies tried are below this
  EiDesign ei_design = EiDesign::damped_fit;  ///< how the EI family is designed
  double freq_step_hz = 0.2;
  double vibration_reduction = 20.0;  ///< PSD below max/this is not counted
  double target_smoothing_mm = 0.12;  ///< for max_accel
};

struct ShaperSelection {
  ShaperCandidate recommended;
  std::vector<ShaperCandidate> candidates;  ///< the chosen frequency of each type, in option order
};

/// Remaining-vibration fraction of a shaper against a PSD (Klipper's measure): the share of
/// the PSD above max(psd)/vibration_reduction that survives the shaper, for one damping ratio.
double remaining_vibrations(const Shaper& s, std::span<const double> freq_hz, std::span<const double> psd,
                            double test_damping_ratio, double vibration_reduction = 20.0);

/// One vibration spectrum a shaper is scored against (frequency bins in Hz and the PSD on them,
/// Klipper-normalized). Bins need not be uniform (Klipper's files round them to 0.1 Hz).
struct PsdDataset {
  std::span<const double> freq_hz;
  std::span<const double> psd;
};

/// Tries every type at frequencies from its minimum to below max_shaper_freq_hz in freq_step_hz
/// steps and picks one by Klipper's published procedure (see docs/resonance.md). `psd` is
/// the vibration PSD (Klipper's normalized psd_xyz). InputError for an empty/flat spectrum.
ShaperSelection select_shaper(std::span<const double> freq_hz, std::span<const double> psd,
                              const ShaperSelectionOptions& options);
/// The same against several spectra at once (several recordings, or the datasets of one Klipper
/// file): a shaper's remaining vibrations are the worst over the datasets, as Klipper scores them.
ShaperSelection select_shaper(std::span<const PsdDataset> datasets, const ShaperSelectionOptions& options);

/// Klipper's per-frequency shaper response for plots and spectrum files: the residual vibration
/// V(f, z) at each frequency, the worst over the test damping ratios.
std::vector<double> shaper_response(const Shaper& s, std::span<const double> freq_hz,
                                    std::span<const double> test_damping_ratios);

}  // namespace tunekit::design
