// tunekit batch: Analyze every dataset in a folder and write one summary.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_batch(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "batch", "Analyze every dataset in a folder and write one summary");
}

}  // namespace tunekit::cli
