// tunekit profile: the command line of the command (options bound straight into the library's
// option structs); the work is done by the calibration library's compute function.

#include <memory>

#include "tunekit/calibration/commands/profile_command.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"

namespace tunekit::cli {

using namespace calibration;

namespace {
struct ProfileCommand {
  ProfileOptions options;
  OutputOptions output;
};
}  // namespace

void register_profile(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ProfileCommand>();
  ProfileOptions& o = cmd->options;
  auto* sub = app.add_subcommand(
      "profile", "A machine profile (TOML) from a Klipper printer.cfg, Marlin M503/Configuration.h or RRF config.g");
  sub->add_option("file", o.file,
                  "Firmware configuration: Klipper printer.cfg (with its [include]s and SAVE_CONFIG block), Marlin "
                  "M503 report or Configuration.h (Configuration_adv.h beside it is read too), RepRapFirmware "
                  "config.g; the format is recognized by the content")
      ->required();
  sub->add_option("-o,--output", o.output_toml, "Write the TOML profile to this file (default: print it)");
  sub->add_flag("--json", cmd->output.json, "Print the profile and the source of every value as JSON on stdout");
  sub->add_option("--sensor", o.sensors,
                  "Declare a sensor the configuration does not list: accelerometer, load_cell, camera, "
                  "filament_encoder (repeatable)");
  sub->add_option("--travel", o.travel_mm, "M503 only: the X, Y and Z travel from 0, mm (e.g. --travel 220,220,250)")
      ->delimiter(',')
      ->expected(3);
  sub->add_option("--hotend-max-c", o.hotend_max_c, "M503 only: the highest hot-end target, degC");
  sub->add_option("--bed-max-c", o.bed_max_c, "M503 only: the highest bed target, degC");
  sub->footer(
      "Every value of the profile names its source: the file and line it was read from, the firmware's default\n"
      "and its formula (e.g. Klipper's max_extrude_only_accel = max_accel * 4 d^2 / (pi (D/2)^2)), or tunekit's\n"
      "default and its reason for what no firmware configuration holds (the hot end's melting limit, the print's\n"
      "line). Calibrate and run read firmware configurations directly too (--profile printer.cfg).\n"
      "Examples:\n"
      "  tunekit profile printer.cfg -o printer.toml\n"
      "  tunekit profile printer.cfg --sensor load_cell --json\n"
      "  tunekit profile Marlin/Configuration.h -o ender3.toml\n"
      "  tunekit profile m503.txt --travel 220,220,250 --hotend-max-c 260 --bed-max-c 110\n"
      "  tunekit profile sys/config.g -o duet.toml");
  sub->callback([cmd, &ctx] { set_exit_code(report_outcome(compute_profile(cmd->options), cmd->output, ctx)); });
}

}  // namespace tunekit::cli
