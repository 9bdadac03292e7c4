// tunekit resonance: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "resonance_cli.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/analyses/resonance_command.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/ringdown.hpp"
#include <algorithm>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct ResonanceCommand {
  ResonanceOptions options;
  OutputOptions output;
};
}  // namespace

CLI::App* add_resonance_command(CLI::App& app, ResonanceOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand(
      "resonance", "Axis resonances from accelerometer data: PSD, modes with natural frequency and damping ratio");
  add_accel_files_options(sub, o.accel, output);
  add_ringdown_options(sub, o.ringdown_options, &o.ringdown);
  sub->footer(klipper_files_help() +
              "\nExamples:\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv /tmp/raw_data_y_*.csv --json\n"
              "  tunekit resonance /tmp/calibration_data_x_20240101.csv\n"
              "  tunekit resonance log.csv --axis y --time t --accel ay --excitation ay_cmd --json -o y.json\n"
              "  tunekit resonance /tmp/raw_data_x_*.csv --require 'x.freq_hz>=40'    # CI drift check\n"
              "  tunekit resonance --ringdown /tmp/adxl345-belt_A.csv   # a plucked belt: fundamental and damping\n"
              "Ring-down analysis: the fundamental and damping ratio of a free decay from a time-domain fit of damped\n"
              "sinusoids (matrix pencil start: Hua and Sarkar, IEEE Trans. ASSP, 1990; least-squares refinement).\n"
              "A record whose decay is below --min-strength times its noise floor is refused with exit 1.");
  return sub;
}

void register_resonance(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ResonanceCommand>();
  add_resonance_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_resonance(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
