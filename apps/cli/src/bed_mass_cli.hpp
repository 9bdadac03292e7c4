#pragma once
// The bed-slinger options of tunekit resonance (--load-kg and what follows from it).

#include <CLI/CLI.hpp>

#include "tunekit/calibration/analyses/bed_mass_command.hpp"

namespace tunekit::cli {

void add_bed_mass_options(CLI::App* sub, calibration::BedMassOptions& o);

}  // namespace tunekit::cli
