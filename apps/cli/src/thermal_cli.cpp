// tunekit thermal: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include <memory>
#include <string>

#include "tunekit/calibration/analyses/thermal_command.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/command.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/option_binding.hpp"

namespace tunekit::cli {

using namespace calibration;

namespace {

struct ThermalCommand {
  ThermalOptions options;
  OutputOptions output;
};

}  // namespace

CLI::App* add_thermal_command(CLI::App& app, ThermalOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand("thermal", "The hot end's thermal model (heater, sensor lag, losses) from a record");
  sub->add_option("record", o.file,
                  "CSV: time, temperature (degC), heater_duty (0..1), optional fan_duty (0..1), feed (mm/s), "
                  "target (degC); the thermal.csv a heater-identify run writes; or a Klipper klippy.log (its "
                  "Stats lines: temperature, target and PWM once a second)")
      ->required();
  sub->add_option("--heater", o.heater, "klippy.log: the heater whose Stats lines are read")->capture_default_str();
  sub->add_option("--until", o.until_s, "Fit only the record's first seconds (s; default: all of it)")
      ->check(positive_finite("seconds"));
  sub->add_option("--heater-power", o.fit.heater_power_w,
                  "Heater power at full duty (W; Marlin's MPC_HEATER_POWER): C, A, F and H are relative to it")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e5));
  sub->add_option("--held-out-from", o.fit.held_out_from_s,
                  "Predict, not fit, the record from this many seconds after its start (default: the "
                  "heater-identify run's held-out part, from its run.json; none without one)");
  add_output_options(sub, output);
  sub->footer(
      "The model is Marlin's MPC form: C dT/dt = u P - (A + f (F - A)) (T - T_a) - H v (T - T_a), the sensor\n"
      "following the block at the rate R. Every parameter has its 95 % interval (docs/thermal.md).\n"
      "Example:\n"
      "  tunekit thermal runs/heater/thermal.csv --heater-power 40 --json --require 'block_heat_capacity_j_per_k<30'\n"
      "  tunekit thermal ~/printer_data/logs/klippy.log --heater extruder --until 300   # a logged heat-up");
  return sub;
}

void register_thermal(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ThermalCommand>();
  add_thermal_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(report_outcome(compute_thermal(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
