// tunekit resonance: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "bed_mass_cli.hpp"
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
  BedMassOptions bed;  ///< --load-kg: the bed slinger's f(m) instead
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
              "  tunekit resonance y0.csv y300.csv --axis y --load-kg 0 --load-kg 0.3 --held-out y150.csv \\\n"
              "      --held-out-load-kg 0.15 --gcode-in part.gcode --gcode-out part.tk.gcode   # a bed slinger's f(m)\n"
              "Ring-down analysis: the fundamental and damping ratio of a free decay from a time-domain fit of damped\n"
              "sinusoids (matrix pencil start: Hua and Sarkar, IEEE Trans. ASSP, 1990; least-squares refinement).\n"
              "A record whose decay is below --min-strength times its noise floor is refused with exit 1.");
  return sub;
}

void register_resonance(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ResonanceCommand>();
  auto* sub = add_resonance_command(app, cmd->options, cmd->output);
  add_bed_mass_options(sub, cmd->bed);
  sub->callback([cmd, &ctx] {
    if (cmd->bed.loads_kg.empty()) {
      set_exit_code(report_outcome(compute_resonance(cmd->options), cmd->output, ctx));
      return;
    }
    cmd->bed.accel = cmd->options.accel;
    set_exit_code(report_outcome(compute_bed_mass(cmd->bed), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
