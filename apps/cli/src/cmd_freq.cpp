// tunekit freq: Liquefier frequency response: sine dwell, broadband H1 and transfer-function fits.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_freq(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "freq", "Liquefier frequency response: sine dwell, broadband H1 and transfer-function fits");
}

}  // namespace tunekit::cli
