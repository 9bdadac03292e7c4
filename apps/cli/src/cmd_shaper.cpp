// tunekit shaper: Input shaper design and recommendation from accelerometer data.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_shaper(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "shaper", "Input shaper design and recommendation from accelerometer data");
}

}  // namespace tunekit::cli
