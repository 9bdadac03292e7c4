// tunekit belts: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "resonance_cli.hpp"
#include "tunekit/calibration/analyses/belts_command.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
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

CLI::App* add_belts_command(CLI::App& app, BeltsOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("belts",
                                 "Compare two belts from a pluck recording of each: fundamentals, tensions in N, "
                                 "which to tighten");
  sub->add_option("belt_a", o.file_a, "Accelerometer CSV of belt A's pluck (#time,accel_x,accel_y,accel_z)")
      ->required();
  sub->add_option("belt_b", o.file_b, "Accelerometer CSV of belt B's pluck")->required();
  sub->add_option("--time", o.input.time_column,
                  fmt::format("Time column (s), strictly increasing (default: {})", o.input.time_column));
  sub->add_option("--accel", o.input.accel_columns,
                  "Acceleration column(s) in mm/s^2 (default: accel_x accel_y accel_z)");
  add_ringdown_options(sub, o.ringdown, nullptr);
  sub->add_option("--max-zeta", o.ringdown.max_zeta,
                  fmt::format("Refuse a pluck whose fundamental is damped more than this (a tap; default {:g})",
                              o.ringdown.max_zeta));
  sub->add_option("--span-mm", o.span_mm,
                  "Free span plucked, between the belt's contact points, mm: gives tensions in N");
  sub->add_option("--span-uncertainty-mm", o.span_uncertainty_mm,
                  fmt::format("Standard uncertainty of the span, mm (default {:g})", o.span_uncertainty_mm));
  sub->add_option("--belt", o.belt,
                  "Belt type for its mass per length: gt2-6mm, gt2-9mm, gt2-10mm, gt2-12mm "
                  "(default gt2-6mm)");
  sub->add_option("--belt-mass-g-m", o.belt_mass_g_m, "The belt's mass per length, g/m (instead of --belt)");
  sub->add_option("--target-n", o.target_n,
                  "Tension to set, N (default: the profile's; without one, match the "
                  "belts to each other)");
  sub->add_option("--profile", o.profile,
                  "Machine profile (TOML) whose [belts] section gives belt, span_mm, "
                  "span_uncertainty_mm, target_n");
  add_output_options(sub, output);
  sub->footer(
      "Each recording holds one pluck: the belt is plucked like a string with the accelerometer on the toolhead\n"
      "(Klipper: ACCELEROMETER_MEASURE, or a belt-tension tool's recorder). The fundamental is the line whose "
      "harmonic\n"
      "series (f, 2f, 3f ...) over the three axes together carries the most power, so a pluck whose second harmonic\n"
      "is the strongest line reads at its fundamental; it is fitted with its harmonics as damped sinusoids on the\n"
      "projection of the axes in which it stands highest over the noise (both are printed).\n"
      "A record that is no pluck is refused with exit 1 and the reason: a decay below --min-strength times the\n"
      "noise floor, no line above the spectrum's floor, a line that does not decay (a fan), one damped more than\n"
      "--max-zeta (a tap).\n"
      "The tension ratio (fA/fB)^2 holds for belts of equal free length and mass per length. With --span-mm the\n"
      "tension of each belt is T = 4 mu L^2 f^2 (taut string; mu 7.569 g/m for 6 mm GT2, Prusa Research's\n"
      "nominal figure, in proportion to width), with a 95 % interval from f and the span's uncertainty.\n"
      "Examples:\n"
      "  tunekit belts /tmp/adxl345-belt_A.csv /tmp/adxl345-belt_B.csv\n"
      "  tunekit belts a.csv b.csv --span-mm 150 --belt gt2-6mm --target-n 20\n"
      "  tunekit belts a.csv b.csv --json --require 'difference_hz<2' --require 'difference_hz>-2'");
  return sub;
}

void register_belts(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<BeltsCommand>();
  add_belts_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_belts(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
