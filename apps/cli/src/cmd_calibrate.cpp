// tunekit calibrate: Guided calibration: experiments, identification, compensators, report.
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

void register_calibrate(CLI::App& app, CliContext& /*ctx*/) {
  add_reserved_command(app, "calibrate", "Guided calibration: experiments, identification, compensators, report");
}

}  // namespace tunekit::cli
