// tunekit run: Run an experiment protocol on a printer or the simulator.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_run(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "run", "Run an experiment protocol on a printer or the simulator");
}

}  // namespace tunekit::cli
