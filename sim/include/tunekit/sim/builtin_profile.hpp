#pragma once
// The machine profile of tunekit's built-in simulated printer (`--machine sim`): the text of
// datasets/machines/sim.toml, built into the library when it is compiled (one file, no copy in
// the sources).

#include <string_view>

#include "tunekit/machine/machine_profile.hpp"

namespace tunekit::sim {

/// The profile's TOML text, byte for byte what datasets/machines/sim.toml held at build time.
std::string_view builtin_sim_profile_toml();

/// That profile, parsed; its source_path is "<built-in simulated printer profile>".
machine::MachineProfile builtin_sim_profile();

}  // namespace tunekit::sim
