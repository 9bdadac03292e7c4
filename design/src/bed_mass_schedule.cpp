#include "tunekit/design/bed_mass_schedule.hpp"

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::design {
namespace {
constexpr double kGramsPerKg = 1000;
constexpr double kMm3PerCm3 = 1000;
// Points at which the chord's deviation from f(m) is sampled.
constexpr int kDeviationSamples = 400;
}  // namespace

double filament_grams_per_mm(double diameter_mm, double density_g_cm3) {
  if (!(diameter_mm > 0) || !(density_g_cm3 > 0))
    throw InputError("the filament's diameter and density must be positive");
  return density_g_cm3 / kMm3PerCm3 * std::numbers::pi / 4 * diameter_mm * diameter_mm;
}

LinearMassSchedule linear_schedule(const ident::BedMassModel& model, double print_mass_g) {
  if (!(print_mass_g > 0) || !std::isfinite(print_mass_g))
    throw InputError(fmt::format("the print's mass must be positive, not {} g", print_mass_g));
  LinearMassSchedule s;
  s.print_mass_g = print_mass_g;
  s.base_hz = model.freq_hz(0);
  s.end_hz = model.freq_hz(print_mass_g / kGramsPerKg);
  s.slope_hz_per_g = (s.end_hz - s.base_hz) / print_mass_g;
  for (int i = 0; i <= kDeviationSamples; ++i) {
    const double m = print_mass_g * i / kDeviationSamples;
    const double d = std::abs(model.freq_hz(m / kGramsPerKg) - (s.base_hz + s.slope_hz_per_g * m));
    if (d > s.max_deviation_hz) s.max_deviation_hz = d, s.max_deviation_at_g = m;
  }
  return s;
}

}  // namespace tunekit::design
