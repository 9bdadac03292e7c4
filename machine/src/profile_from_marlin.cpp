// A machine profile from a Marlin M503 report or Configuration.h: recognized, not imported yet.
#include "tunekit/core/error.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {

MachineProfile profile_from_marlin(const std::string& path, const ProfileImportOptions&) {
  throw InputError("Marlin configurations are recognized but not imported yet", path);
}

}  // namespace tunekit::machine
