#pragma once
// Input shaping scheduled with the print's mass on a bed slinger (ident/bed_mass.hpp gives the
// bed axis' f(m)). Firmware that moves the frequency itself takes a straight line:
//   Marlin FT_MOTION M493 D2   f = base + K E      (E: the extruder's position, mm of filament)
//   Prusa Buddy M74/M593       f = F + A min(W, M) / M   (W: the mass on the bed, g)
// linear_schedule() gives the chord of f(m) from the empty bed to the print's mass and how far
// f(m) bends away from it in between. Firmware that takes one frequency (Klipper's
// SET_INPUT_SHAPER) gets a value per layer from the layer's mass, written only where it moved by
// more than a stated step (firmware/bed_mass_export.hpp).

#include "tunekit/ident/bed_mass.hpp"

namespace tunekit::design {

/// Grams per mm of filament of diameter `diameter_mm` and density `density_g_cm3`.
double filament_grams_per_mm(double diameter_mm, double density_g_cm3);

/// The straight line through f(0) and f(M) over the masses 0 .. M (M = `print_mass_g`).
struct LinearMassSchedule {
  double print_mass_g = 0;
  double base_hz = 0;             ///< f with the empty bed
  double end_hz = 0;              ///< f with the whole print on the bed
  double slope_hz_per_g = 0;      ///< (end - base) / M, negative
  double max_deviation_hz = 0;    ///< largest |f(m) - line(m)| over 0 .. M
  double max_deviation_at_g = 0;  ///< where it is
};
LinearMassSchedule linear_schedule(const ident::BedMassModel& model, double print_mass_g);

}  // namespace tunekit::design
