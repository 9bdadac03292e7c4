#pragma once
// A belt span's tension from its transverse vibration: the taut-string model
//   T = 4 mu L^2 f^2
// (T in N, mu the belt's mass per length in kg/m, L the free span in m, f the fundamental in
// Hz), the relation belt tension meters use (Gates Corporation, "Sonic Tension Meter model
// 508C manual", 2013: T = 4 M W S^2 f^2 x 10^-9 with M in g/(m mm) of width W in mm and S in mm;
// the same formula in Prusa Research's belt-tuning firmware, Prusa-Firmware-Buddy, 2024).
// A belt is stiffer than a string, so for spans shorter than some 20 tooth pitches the model
// reads high (the same manual).
//
// Linear mass: 7.569 g/m for a 6 mm GT2 belt, the nominal figure of Prusa Research's
// belt-tuning firmware (Prusa-Firmware-Buddy, 2024), scaled in proportion to width for the
// other widths as the Gates manual's per-width constant does. A belt of another make or
// construction (steel or aramid cord, a wider tooth) differs: give its mass with the option.

#include <string>
#include <vector>

namespace tunekit::ident {

struct BeltSpec {
  std::string name;  ///< e.g. "gt2-6mm"
  double width_mm = 0;
  double mass_kg_m = 0;  ///< linear mass, kg/m
};

/// The belts known by name (GT2 6, 9, 10 and 12 mm).
const std::vector<BeltSpec>& belt_specs();
/// The belt of that name (case-insensitive); InputError naming the known ones otherwise.
const BeltSpec& belt_spec(const std::string& name);

struct StringTension {
  double tension_n = 0;
  double stderr_n = 0;  ///< from the frequency's and the span's standard errors (delta method)
  double ci95_lo = 0, ci95_hi = 0;
};

/// T = 4 mu L^2 f^2 with u(T)/T = 2 sqrt((u_f/f)^2 + (u_L/L)^2). InputError for a non-positive
/// mass, span or frequency.
StringTension string_tension(double mass_kg_m, double span_m, double span_stderr_m, double freq_hz,
                             double freq_stderr_hz);

/// The fundamental (Hz) of a span of L m at tension T N: f = sqrt(T / (4 mu L^2)).
double string_frequency(double mass_kg_m, double span_m, double tension_n);

}  // namespace tunekit::ident
