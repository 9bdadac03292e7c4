#pragma once
// Input-shaper definitions (Singer & Seering 1990; Singhose, Seering & Singer 1994/1997;
// Singhose 2009 review): the named impulse sequences as functions of the design frequency and
// damping ratio, as Klipper's shaper definitions (Butyugin, 2020) hold them for its runtime and
// its calibration alike. The simulator shapes its moves with these; the design of a shaper
// against a measured spectrum (design/input_shaper.hpp) builds on them.
//
// Shaper names are spelled as Klipper spells them: "zv", "mzv", "zvd", "ei", "2hump_ei",
// "3hump_ei", plus "zvdd". Amplitudes are normalized to sum to 1, times start at 0 and are in
// seconds.

#include <string>
#include <vector>

namespace tunekit::design {

enum class ShaperType { zv, mzv, zvd, zvdd, ei, two_hump_ei, three_hump_ei };

/// "zv", "mzv", "zvd", "zvdd", "ei", "2hump_ei", "3hump_ei".
std::string to_string(ShaperType t);
/// Parses a Klipper shaper name (case-insensitive); InputError for an unknown name.
ShaperType parse_shaper_type(const std::string& name);
/// Every shaper type, shortest first.
const std::vector<ShaperType>& all_shaper_types();

struct ShaperInfo {
  ShaperType type;
  double min_freq_hz;        ///< lowest frequency tried in automatic selection (Klipper's values)
  double max_damping_ratio;  ///< validity limit of the design formulas
};
const ShaperInfo& shaper_info(ShaperType t);

/// Klipper's tolerated remaining vibration of the EI family (1/20 = 5 %).
inline constexpr double kDefaultVibrationTolerance = 0.05;

struct Shaper {
  ShaperType type = ShaperType::zv;
  double freq_hz = 0;
  double damping_ratio = 0;
  std::vector<double> amplitudes;  ///< sum to 1
  std::vector<double> times_s;     ///< increasing, first is 0

  double duration_s() const { return times_s.empty() ? 0.0 : times_s.back(); }
};

/// How the EI family (ei, 2hump_ei, 3hump_ei) accounts for damping. ZV, ZVD, ZVDD and MZV
/// have exact damped closed forms and do not depend on this.
enum class EiDesign {
  /// Singhose's undamped closed forms, impulse i scaled by K^i (an approximation for z > 0).
  closed_form,
  /// Singhose's polynomial fits of the damped EI solutions in the damping ratio (EI: in V and
  /// z; 2-hump and 3-hump EI: z, for V = 5 % only): Singhose, Seering and Singer, Vibration
  /// Reduction Using Multi-Hump Input Shapers, ASME J. Dyn. Sys. Meas. Control, 1997. These are
  /// the shapers Klipper runs (its shaper definitions, Butyugin, 2020), valid up to the type's
  /// max_damping_ratio.
  damped_fit,
};

/// Impulse sequence of `type` for a mode at `freq_hz` with `damping_ratio` (0 <= z < 1).
/// Closed forms: ZV, ZVD, ZVDD (Singer-Seering), MZV (Klipper); the EI family as `ei_design`
/// says. Throws InputError for a non-positive frequency, a damping ratio outside [0, 1), or a
/// damped-fit 2-hump/3-hump EI with a vibration tolerance other than 5 %.
Shaper design_shaper(ShaperType type, double freq_hz, double damping_ratio,
                     double vibration_tolerance = kDefaultVibrationTolerance,
                     EiDesign ei_design = EiDesign::closed_form);

}  // namespace tunekit::design
