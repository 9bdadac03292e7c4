// tunekit report: rebuild the self-contained HTML report of a run directory from its
// results.json and plotdata.json.
#include <memory>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/report_command.hpp"

namespace tunekit::cli {

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
