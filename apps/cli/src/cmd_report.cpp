// tunekit report: Rebuild the HTML report of a run directory.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_report(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "report", "Rebuild the HTML report of a run directory");
}

}  // namespace tunekit::cli
