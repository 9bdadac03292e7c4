// tunekit resonance: Axis resonances from accelerometer data: PSD, modes with damping.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_resonance(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "resonance", "Axis resonances from accelerometer data: PSD, modes with damping");
}

}  // namespace tunekit::cli
