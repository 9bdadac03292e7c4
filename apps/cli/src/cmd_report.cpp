// tunekit report: rebuild the self-contained HTML report of a run directory from its
// results.json and plotdata.json.
#include <memory>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/report.hpp"

namespace tunekit::cli {

void register_report(CLI::App& app, CliContext& ctx) {
  auto dir = std::make_shared<std::string>();
  auto* sub = app.add_subcommand("report", "Rebuild the HTML report of a run directory");
  sub->add_option("run_dir", *dir, "Run directory written by 'tunekit calibrate' (holds results.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->footer("Example:\n  tunekit report runs/20261122-sim-1\nWrites RUN_DIR/report.html (plots embedded; opens offline) and prints its path.");
  sub->callback([dir, &ctx] {
    const std::string path = write_report(*dir);
    ctx.out << path << "\n";
  });
}

}  // namespace tunekit::cli
