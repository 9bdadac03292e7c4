// tunekit step: Identify liquefier dynamics (K, tau, theta) from step-response logs.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_step(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "step", "Identify liquefier dynamics (K, tau, theta) from step-response logs");
}

}  // namespace tunekit::cli
