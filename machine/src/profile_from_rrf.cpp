// A machine profile from a RepRapFirmware config.g: recognized, not imported yet.
#include "tunekit/core/error.hpp"
#include "tunekit/machine/profile_import.hpp"

namespace tunekit::machine {

MachineProfile profile_from_rrf(const std::string& path, const ProfileImportOptions&) {
  throw InputError("RepRapFirmware configurations are recognized but not imported yet", path);
}

}  // namespace tunekit::machine
