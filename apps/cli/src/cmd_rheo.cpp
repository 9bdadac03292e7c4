// tunekit rheo: Fit melt viscosity models (power law, Cross, Cross-WLF, Carreau-Yasuda).
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_rheo(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "rheo", "Fit melt viscosity models (power law, Cross, Cross-WLF, Carreau-Yasuda)");
}

}  // namespace tunekit::cli
