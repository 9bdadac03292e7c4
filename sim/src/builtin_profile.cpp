#include "tunekit/sim/builtin_profile.hpp"

#include <string>

namespace tunekit::sim {

machine::MachineProfile builtin_sim_profile() {
  return machine::parse_machine_profile(std::string(builtin_sim_profile_toml()),
                                        "<built-in simulated printer profile>");
}

}  // namespace tunekit::sim
