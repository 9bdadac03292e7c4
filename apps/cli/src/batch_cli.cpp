// tunekit batch: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/commands/batch_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/results/requirements.hpp"
#include "tunekit/calibration/analyses/rheo_command.hpp"
#include "tunekit/calibration/analyses/shaper_command.hpp"
#include "tunekit/calibration/analyses/step_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <thread>

namespace tunekit::cli {

using namespace calibration;

void register_batch(CLI::App& app, CliContext& ctx) {
  auto a = std::make_shared<BatchArgs>();
  auto* sub = app.add_subcommand("batch", "Analyze every dataset in a folder in parallel and write one summary");
  sub->add_option("dir", a->dir, "Folder of datasets (CSV files)")->required()->check(CLI::ExistingDirectory);
  sub->add_option("-j,--jobs", a->jobs, "Parallel analyses (default: one per core)");
  add_output_options(sub, a->output);
  sub->footer(
      "Each CSV is recognized by its columns: accel_x/y/z or freq+psd_x -> shaper; time+feed+force -> step,\n"
      "or freq when the feed changes level faster than a liquefier settles (a chirp);\n"
      "shear_rate+viscosity -> rheo. Exit code: the worst of the datasets (0 ok, 1 fit failed or requirement\n"
      "unmet, 2 bad input).\n"
      "Example:\n  tunekit batch archive/2026-11/ --require 'tau_s<0.6' --require 'x.freq_hz>=35' -o summary.json");
  sub->callback([a, &ctx] { set_exit_code(run_batch(*a, ctx)); });
}

}  // namespace tunekit::cli
