// tunekit report: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/presentation/report_command.hpp"
#include <memory>

namespace tunekit::cli {

using namespace calibration;

void register_report(CLI::App& app, CliContext& ctx) {
  auto options = std::make_shared<ReportOptions>();
  auto* sub = app.add_subcommand("report", "Rebuild the HTML report of a run directory");
  sub->add_option("run_dir", options->run_dir, "Run directory written by 'tunekit calibrate' (holds results.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->footer(
      "Example:\n  tunekit report runs/20261122-sim-1\nWrites RUN_DIR/report.html (plots embedded; opens offline) and "
      "prints its path.");
  sub->callback([options, &ctx] { print_text(compute_report(*options), ctx.out); });
}

}  // namespace tunekit::cli
