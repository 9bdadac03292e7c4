// Simulated delta probing: see delta_probe_sim.hpp.
#include "tunekit/sim/delta_probe_sim.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include <fmt/format.h>

#include "tunekit/core/error.hpp"

namespace tunekit::sim {

std::vector<ident::DeltaProbe> delta_probe_pattern(double radius_mm, int rings, int points_per_ring) {
  if (!(radius_mm > 0) || rings < 1 || points_per_ring < 3)
    throw InputError("probe pattern needs a radius > 0 mm, at least 1 ring and 3 points per ring");
  std::vector<ident::DeltaProbe> p{{0, 0, 0}};
  for (int k = 1; k <= rings; ++k) {
    const double r = radius_mm * k / rings;
    for (int j = 0; j < points_per_ring; ++j) {
      const double a = std::numbers::pi / 2 + 2 * std::numbers::pi * j / points_per_ring;
      p.push_back({r * std::cos(a), r * std::sin(a), 0});
    }
  }
  return p;
}

std::vector<ident::DeltaProbe> simulate_delta_probes(const ident::DeltaGeometry& nominal,
                                                     const ident::DeltaGeometry& truth,
                                                     std::vector<ident::DeltaProbe> points, double noise_sd_mm,
                                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_sd_mm > 0 ? noise_sd_mm : 1.0);
  for (auto& p : points) {
    try {
      p.z_mm = ident::delta_probe_height(nominal, truth, p.x_mm, p.y_mm);
    } catch (const std::runtime_error& e) {
      throw InputError(fmt::format("simulated probe at ({:g}, {:g}) mm: {}", p.x_mm, p.y_mm, e.what()));
    }
    if (noise_sd_mm > 0) p.z_mm += noise(rng);
  }
  return points;
}

}  // namespace tunekit::sim
