#pragma once
// Simulated delta probing: the heights a G30 probe reports on a delta whose real geometry
// differs from the geometry its firmware runs (the geometric errors are the truth), plus
// Gaussian probe noise. A separate mode beside the G-code simulator.
#include <cstdint>
#include <vector>

#include "tunekit/ident/delta_kinematics.hpp"

namespace tunekit::sim {

/// A probe pattern as RepRapFirmware's delta bed.g files use: the centre, then `rings`
/// circles (radii radius_mm * k / rings) of `points_per_ring` points, the first at a tower
/// angle (90 degrees). Coordinates in mm.
std::vector<ident::DeltaProbe> delta_probe_pattern(double radius_mm, int rings, int points_per_ring);

/// The heights (z_mm filled in for every (x_mm, y_mm) of `points`) that a firmware running
/// `nominal` measures on a flat bed when the machine's real geometry is `truth`, plus
/// N(0, noise_sd_mm^2) noise from a generator seeded with `seed`.
std::vector<ident::DeltaProbe> simulate_delta_probes(const ident::DeltaGeometry& nominal,
                                                     const ident::DeltaGeometry& truth,
                                                     std::vector<ident::DeltaProbe> points, double noise_sd_mm,
                                                     std::uint64_t seed);

}  // namespace tunekit::sim
