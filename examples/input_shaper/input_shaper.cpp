// Design input shapers for a measured axis resonance and compare them.
//
// An input shaper replaces each acceleration step by a few smaller steps (impulses) timed so
// that the vibration they excite in a lightly damped mode cancels (Singer and Seering,
// Preshaping Command Inputs to Reduce System Vibration, 1990; Singhose, Seering and Singer,
// Vibration Reduction Using Multi-Hump Input Shapers, 1997). The price is smoothing: corners
// are rounded, more so at higher acceleration. For each shaper this program prints its
// impulses, the vibration left when the real mode is 20 % off the design frequency, the
// smoothing at 5000 mm/s^2, and the highest acceleration that keeps the smoothing below
// 0.12 mm (the limit Klipper uses for its recommendation).
//
//   input_shaper [FREQUENCY_HZ [DAMPING_RATIO]]      defaults: 42 Hz, 0.05
//
// The frequency and damping ratio come from a resonance measurement (`tunekit shaper` fits
// them from an accelerometer recording; ident/resonance.hpp is the library call).

#include <cstdio>
#include <cstdlib>
#include <exception>

#include "tunekit/design/input_shaper.hpp"

namespace sd = tunekit::design;

int main(int argc, char** argv) {
  const double freq_hz = argc > 1 ? std::strtod(argv[1], nullptr) : 42.0;
  const double zeta = argc > 2 ? std::strtod(argv[2], nullptr) : 0.05;
  std::printf("resonance %.1f Hz, damping ratio %.3f\n", freq_hz, zeta);

  try {
    for (sd::ShaperType type :
         {sd::ShaperType::zv, sd::ShaperType::mzv, sd::ShaperType::ei, sd::ShaperType::two_hump_ei}) {
      // 1. The impulse sequence, designed at the measured frequency and damping. The EI family
      //    is designed as Klipper runs it (Singhose's damped fits); vibration tolerance 5 %.
      const sd::Shaper s =
          sd::design_shaper(type, freq_hz, zeta, sd::kDefaultVibrationTolerance, sd::EiDesign::damped_fit);
      std::printf("%-8s %zu impulses over %5.1f ms:", sd::to_string(type).c_str(), s.amplitudes.size(),
                  1e3 * s.duration_s());
      for (std::size_t i = 0; i < s.amplitudes.size(); ++i)
        std::printf(" %.3f@%.1fms", s.amplitudes[i], 1e3 * s.times_s[i]);
      std::printf("\n");

      // 2. Robustness: the vibration left (fraction of the unshaped one) when the mode is not
      //    where the shaper was designed for, e.g. because the toolhead's load changed.
      // 3. Cost: smoothing at 5000 mm/s^2 (square-corner velocity 5 mm/s), and the largest
      //    acceleration with at most 0.12 mm of smoothing.
      std::printf(
          "         vibration left at 0.8 f %4.1f %%, at f %4.1f %%, at 1.2 f %4.1f %%; "
          "smoothing %.3f mm; max accel %.0f mm/s^2\n",
          100 * sd::residual_vibration(s, 0.8 * freq_hz, zeta), 100 * sd::residual_vibration(s, freq_hz, zeta),
          100 * sd::residual_vibration(s, 1.2 * freq_hz, zeta), sd::shaper_smoothing(s, 5000.0, 5.0),
          sd::shaper_max_accel(s, 5.0, 0.12));
    }
  } catch (const std::exception& e) {  // e.g. a non-positive frequency or damping ratio >= 1
    std::fprintf(stderr, "input_shaper: %s\n", e.what());
    return 2;
  }
  return 0;
}
