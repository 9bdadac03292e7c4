#pragma once
// The bed axis' frequency scheduled with the print's mass (design/bed_mass_schedule.hpp), in each
// firmware's own words:
//
//   Marlin FT_MOTION, mass-based dynamic frequency (Marlin/src/gcode/feature/ft_motion/M493.cpp
//   and ft_motion.cpp, bugfix-2.1.x as read in 2024 and 2026): "M493 D2" turns it on once an axis
//   is shaped; the shaper then runs at baseFreq + dynFreqK * e, e the extruder's position in mm
//   (the planner's E: G92 E resets it, so the schedule holds only for a file that never resets
//   E). The scaling is F (X) and H (Y) in the forms that set shapers with X/Y<shaper> (2024-2025),
//   "M493 Y F<K>" in FTM V2 (2025-), in Hz per mm of filament (the report prints "Hz/g").
//   Prusa Buddy (lib/Marlin/Marlin/src/gcode/feature/input_shaper/M593.cpp, M74.cpp and
//   feature/input_shaper/input_shaper_config.hpp, Prusa-Firmware-Buddy 6.3.0, 2025): "M593 Y T<type>
//   F<Hz> D<damping>" sets the Y shaper, "M593 A<Hz> M<g>" its weight adjustment (A below 0, M at
//   least 0; the Y frequency moves linearly from F to F + A as the mass goes from 0 to M, and stays
//   at F + A beyond), "M74 W<g>" tells the firmware the mass on the bed; frequencies are clamped
//   to 10 .. 100 Hz (150 on the MINI).
//   Klipper and Kalico: "SET_INPUT_SHAPER SHAPER_FREQ_Y=<Hz>" (klippy/extras/input_shaper.py)
//   per layer from the layer's mass, inserted into the sliced G-code.

#include <string>
#include <vector>

#include "tunekit/design/bed_mass_schedule.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/firmware/marlin_m493.hpp"

namespace tunekit::firmware {

/// The M493 lines of Marlin's mass-based dynamic frequency on Y: the Y shaper (ftMotionShaper_t
/// `shaper_code`, base `schedule.base_hz`, damping `zeta`), D2, and the Y scaling in Hz per mm
/// of filament (`grams_per_mm` turns the schedule's Hz/g into it). InputError for the 2023 mode
/// form (its dynamic-frequency letters were not checked) or no form.
std::vector<std::string> marlin_mass_schedule_lines(const M493Syntax& syntax, int shaper_code, double zeta,
                                                    const design::LinearMassSchedule& schedule, double grams_per_mm);
/// The scaling (Hz per mm of filament) Marlin's M493 D2 takes.
double marlin_hz_per_mm(const design::LinearMassSchedule& schedule, double grams_per_mm);

/// Prusa Buddy's shaper type number for M593 T (0 ZV, 1 ZVD, 2 MZV, 3 EI, 4 2HUMP_EI, 5 3HUMP_EI);
/// InputError for another shaper.
int prusa_shaper_type(const std::string& shaper);
/// "M593 Y T<type> F<base> D<zeta>" and "M593 A<delta> M<print mass>". InputError when the base
/// or end frequency is outside 10 .. 100 Hz (the firmware would clamp it) or the delta is not
/// below 0 (the firmware refuses it).
std::vector<std::string> prusa_weight_adjust_lines(const std::string& shaper, double zeta,
                                                   const design::LinearMassSchedule& schedule);

/// What the post-processor writes at a layer change: Klipper's and Kalico's SET_INPUT_SHAPER
/// SHAPER_FREQ_Y=<Hz>, or Prusa Buddy's M74 W<g> (the firmware then moves the frequency itself).
enum class MassScheduleCommand { set_input_shaper, prusa_m74 };

struct GcodeMassScheduleOptions {
  MassScheduleCommand command = MassScheduleCommand::set_input_shaper;
  double grams_per_mm = 0;               ///< of filament (design::filament_grams_per_mm)
  double min_step_hz = 0.5;              ///< a new value only beyond this change
  double configured_hz = fitting::kNaN;  ///< the printer's setting; NaN: the empty bed's f(0)
};
/// One inserted command: before the layer that starts after original line `line` (1-based).
struct GcodeMassChange {
  std::size_t line = 0;
  std::size_t layer = 0;  ///< 0-based layer
  double mass_g = 0;
  double freq_hz = 0;
  std::string command;
};
struct GcodeMassResult {
  std::string text;
  std::vector<GcodeMassChange> changes;
  std::size_t layers = 0;
  std::vector<double> layer_mass_g;  ///< on the bed when each layer starts
  double print_mass_g = 0;           ///< the file's net extrusion, in grams
  bool resets_e = false;             ///< the file resets E (G92 E) while printing
  std::vector<std::string> warnings;
};
/// Inserts the per-layer frequency (Klipper, Kalico) or mass (Prusa M74 W) after each layer
/// change the slicer marks (";LAYER_CHANGE", PrusaSlicer, OrcaSlicer, SuperSlicer; ";LAYER:",
/// Cura) where it moved by more than the step. The mass on the bed when a layer starts is the
/// net extrusion before it (retractions subtract, primes add back; M82/M83 and G92 E followed)
/// times grams_per_mm. Every original line is kept byte for byte. InputError (with `path`) when
/// the file marks no layer.
GcodeMassResult apply_gcode_mass_schedule(const std::string& text, const ident::BedMassModel& model,
                                          const GcodeMassScheduleOptions& options, const std::string& path);

}  // namespace tunekit::firmware
