// tunekit linewidth: Calibrated width profiles of printed lines from photos.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_linewidth(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "linewidth", "Calibrated width profiles of printed lines from photos");
}

}  // namespace tunekit::cli
