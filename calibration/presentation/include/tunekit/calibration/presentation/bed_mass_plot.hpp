#pragma once
// The bed slinger's figure: the bed axis' f(m) with its 95 % band over the masses of interest, the
// sweeps it was fitted to and those it predicted; below it, when a sliced print was scheduled, the
// print's mass on the bed over its layers with the frequency each layer runs at.

#include <vector>

#include "tunekit/calibration/presentation/plots.hpp"
#include "tunekit/ident/bed_mass.hpp"

namespace tunekit::calibration {

/// `layer_mass_g`: the print's mass on the bed when each layer starts (empty: no second panel).
Figure bed_mass_figure(const ident::BedMassFit& fit, const std::vector<ident::BedHeldOutCheck>& held_out,
                       const std::vector<double>& layer_mass_g);

}  // namespace tunekit::calibration
