// tunekit belts: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "resonance_cli.hpp"
#include "tunekit/calibration/belts_command.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include <cmath>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {
struct BeltsCommand {
  BeltsOptions options;
  OutputOptions output;
};
}  // namespace

void register_belts(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<BeltsCommand>();
  BeltsOptions& o = cmd->options;
  auto* sub = app.add_subcommand("belts",
                                 "Compare two belts from a pluck recording of each: frequencies, difference, "
                                 "tension ratio");
  sub->add_option("belt_a", o.file_a, "Accelerometer CSV of belt A's pluck (#time,accel_x,accel_y,accel_z)")
      ->required();
  sub->add_option("belt_b", o.file_b, "Accelerometer CSV of belt B's pluck")->required();
  sub->add_option("--time", o.input.time_column,
                  fmt::format("Time column (s), strictly increasing (default: {})", o.input.time_column));
  sub->add_option("--accel", o.input.accel_columns,
                  "Acceleration column(s) in mm/s^2 (default: accel_x accel_y accel_z)");
  add_ringdown_options(sub, o.ringdown, nullptr);
  add_output_options(sub, cmd->output);
  sub->footer(
      "Each recording holds one pluck: the belt is plucked like a string with the accelerometer on the toolhead\n"
      "(Klipper: ACCELEROMETER_MEASURE, or a belt-tension tool's recorder). The fundamental is found harmonic-aware\n"
      "(a line at 2f with a weaker line at f is f's harmonic) and fitted as a damped sinusoid in the time domain.\n"
      "A pluck whose decay is below --min-strength times the noise floor is refused with exit 1.\n"
      "The tension ratio (fA/fB)^2 holds for belts of equal free length and mass per length.\n"
      "Examples:\n"
      "  tunekit belts /tmp/adxl345-belt_A.csv /tmp/adxl345-belt_B.csv\n"
      "  tunekit belts a.csv b.csv --json --require 'difference_hz<2' --require 'difference_hz>-2'");
  sub->callback([cmd, &ctx] { set_exit_code(report_outcome(compute_belts(cmd->options), cmd->output, ctx)); });
}

}  // namespace tunekit::cli
