// tunekit ports: List serial ports.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_ports(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "ports", "List serial ports");
}

}  // namespace tunekit::cli
