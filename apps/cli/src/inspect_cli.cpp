// tunekit inspect: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/analyses/inspect_command.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/formats/csv.hpp"
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct InspectCommand {
  InspectOptions options;
  OutputOptions output;
};

}  // namespace

void register_inspect(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<InspectCommand>();
  InspectOptions& o = cmd->options;
  auto* sub = app.add_subcommand("inspect", "Check that a time-series CSV is readable and summarize it");
  sub->add_option("file", o.file, "CSV file (comment lines start with '#'; units allowed in names: 'force (N)')")
      ->required();
  sub->add_option("-t,--time", o.time_column, "Name of the time column (s); must strictly increase");
  sub->add_option("-c,--columns", o.columns, "Columns to read (default: all)");
  add_output_options(sub, cmd->output);
  sub->footer(
      "Examples:\n"
      "  tunekit inspect datasets/liquefier/holtrup_table_b1_ooze.csv\n"
      "  tunekit inspect adxl345-x.csv --time time --json     # a Klipper raw accelerometer file");
  sub->callback([cmd, &ctx] { set_exit_code(report_outcome(compute_inspect(cmd->options), cmd->output, ctx)); });
}

}  // namespace tunekit::cli
