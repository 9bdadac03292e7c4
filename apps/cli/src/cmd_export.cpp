// tunekit export: Write pressure advance and input shaping into firmware configuration.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_export(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "export", "Write pressure advance and input shaping into firmware configuration");
}

}  // namespace tunekit::cli
