// tunekit nozzle: Nozzle pressure drop from rheology and geometry, and its inverse fit.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_nozzle(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "nozzle", "Nozzle pressure drop from rheology and geometry, and its inverse fit");
}

}  // namespace tunekit::cli
