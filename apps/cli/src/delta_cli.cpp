// tunekit delta: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/analyses/delta_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/delta_export.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/delta_calibration.hpp"
#include <cmath>
#include <fmt/format.h>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct DeltaCommand {
  DeltaOptions options;
  OutputOptions output;
};

}  // namespace

CLI::App* add_delta_command(CLI::App& app, DeltaOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("delta", "Delta printer calibration: fit geometric errors to probe heights, export");
  sub->add_option("probes", o.probes_csv, "CSV of probe heights: x_mm,y_mm,z_mm (G30 S-1 trigger heights)")->required();
  sub->add_option("-f,--factors", o.factors,
                  "Factors: 3 endstops, 4 +radius, 6 +tower angles A/B, 7 +rod, 8 = 6 +bed tilt, 9 = 7 +tilt")
      ->capture_default_str();
  sub->add_option("--radius", o.radius_mm, "Firmware's delta radius while probing (mm)");
  sub->add_option("--rod", o.rod_mm, "Firmware's diagonal rod length, one or three values (mm)")->delimiter(',');
  sub->add_option("--height", o.height_mm,
                  "Firmware's homed height H (mm; Klipper: position_endstop - endstop adjustment)");
  sub->add_option("--angles", o.angles_deg, "Firmware's tower angles A,B,C (deg)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--endstops", o.endstops_mm, "Firmware's endstop adjustments A,B,C (mm)")
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--export", o.export_firmware, "Print the fitted settings for klipper, marlin or rrf");
  sub->add_option("--export-file", o.export_file, "Write the exported settings to this file (atomically)");
  sub->add_option("--print-radius", o.print_radius_mm, "RepRapFirmware's M665 B, printable radius (mm)");
  sub->add_option("--marlin-probe-z-offset", o.marlin_probe_z_offset_mm,
                  "Marlin's M851 Z (mm): with a bed probe Marlin homes at M665 H minus it")
      ->capture_default_str();
  sub->add_option("--max-rows", o.max_rows, "Most probe rows accepted (count); a longer file is refused")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{100000000}));
  add_output_options(sub, output);
  sub->footer(
      "Probe heights come from a CSV (probing over the machine link is not built in yet).\n"
      "Factor sets as RepRapFirmware's G32; the 6-factor set is Klipper's DELTA_CALIBRATE set.\n"
      "Example:\n"
      "  tunekit delta probes.csv --radius 105 --rod 215 --height 250 --factors 6 --export klipper");
  return sub;
}

void register_delta(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<DeltaCommand>();
  add_delta_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_delta(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
