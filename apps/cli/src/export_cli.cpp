// tunekit export: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/commands/export_command.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/presentation/plots.hpp"
#include "tunekit/calibration/results/results_json.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/firmware/config_edit.hpp"
#include "tunekit/firmware/firmware_export.hpp"
#include "tunekit/firmware/firmware_limits.hpp"
#include "tunekit/firmware/gcode_advance.hpp"
#include "tunekit/firmware/orca_profile.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/design/flow_advance.hpp"
#include "tunekit/design/pressure_advance.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct ExportCommand {
  ExportOptions options;
  OutputOptions output;
};

// An option whose value must be a finite number: "nan", "inf" and "1e400" are refused with the
// words the user typed.
CLI::Option* export_finite_option(CLI::App* sub, const std::string& name, double& target, const char* unit,
                                  const std::string& description) {
  return sub
      ->add_option_function<std::string>(
          name,
          [&target, name, unit](const std::string& raw) {
            double v = 0;
            if (!CLI::detail::lexical_cast(raw, v))
              throw CLI::ConversionError("Could not convert: " + name + " = " + raw);
            if (!std::isfinite(v))
              throw InputError(fmt::format("{} must be a finite number ({}), not '{}'", name, unit, raw));
            target = v;
          },
          description)
      ->type_name("FLOAT");
}

}  // namespace

CLI::App* add_export_command(CLI::App& app, ExportOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand(
      "export",
      "Write pressure advance, input shaping and the hot end's temperature control into firmware configuration "
      "(diff preview; --write applies)");
  sub->add_option("results", o.results,
                  "JSON results of 'tunekit step', 'freq', 'shaper' and/or 'rheo' (any number, any order)");
  sub->add_option("-f,--firmware", o.firmware,
                  "Firmware dialect: klipper, kalico (nonlinear advance from two or more flow levels), marlin or rrf")
      ->required();
  sub->add_option("-c,--config", o.config,
                  "Configuration file to edit: printer.cfg (klipper), Configuration_adv.h (marlin), config.g (rrf)")
      ->required();
  sub->add_option("-p,--profile", o.profile,
                  "Machine profile TOML (filament diameter mm, line width/height mm, print speed mm/s, print and "
                  "extruder acceleration mm/s^2) for the smoothing time");
  export_finite_option(sub, "--pa-k", o.pa_k, "s", "Advance K in s (mm of filament per mm/s), instead of the results");
  export_finite_option(
      sub, "--pa-smooth", o.pa_smooth, "s",
      "Smoothing time in s (Klipper pressure_advance_smooth_time, Marlin ADVANCE_TAU), instead of the design");
  export_finite_option(
      sub, "--design-flow", o.design_flow, "mm^3/s",
      "Volumetric flow in mm^3/s the single advance value is designed for (default: print speed x line "
      "cross-section)");
  sub->add_option("--shaper-x", o.shaper_x, "X shaper TYPE:FREQ[:ZETA] (frequency in Hz, damping ratio 0-1)");
  sub->add_option("--shaper-y", o.shaper_y, "Y shaper TYPE:FREQ[:ZETA] (frequency in Hz, damping ratio 0-1)");
  sub->add_option("--shaper-z", o.shaper_z,
                  "Z shaper TYPE:FREQ[:ZETA] (Klipper only: shaper_type_z, shaper_freq_z, damping_ratio_z)");
  sub->add_option("--extruder", o.extruder,
                  "Extruder: a Klipper section name (default: extruder), or a number N: Klipper [extruderN], Marlin's "
                  "Nth ADVANCE_K entry (M900 TN), RepRapFirmware drive N");
  sub->add_option("--drive", o.drive, "RepRapFirmware extruder drive number for M572 D (default: 0)")
      ->each([&opts = o](const std::string&) { opts.drive_given = true; });
  sub->add_flag("--marlin-ft-motion", o.marlin_ft_live,
                "The running Marlin reports fixed-time motion enabled (M493): shapers among FT_MOTION's, runtime "
                "G-code M493 instead of M593/M900 (tunekit calibrate sets it from the printer's answer)");
  sub->add_option("--marlin-m493-form", o.marlin_m493_form,
                  "With --marlin-ft-motion: the form of the printer's M493 report, whose letters the G-code uses: "
                  "mode (2023), axis_slash (2024), axis_named (2024-2025, the default), axis_list (2025), "
                  "axis_list_v2 (late 2025 on, M493 V answers FTM V2), or none (not known: axis_named, with a "
                  "warning); tunekit run records it in run.json");
  sub->add_option("--thermal-model", o.thermal_model,
                  "Hot end thermal model P:C:R:A:F[:H] (W, J/K, 1/s, W/K, W/K, J/(K mm)) instead of the results of "
                  "'tunekit thermal': Marlin MPC (Configuration.h), Kalico MPC, Klipper PID, RepRapFirmware M307");
  sub->add_flag("--no-thermal", o.no_thermal, "Leave the temperature control alone");
  sub->add_option("--heater", o.heater, "RepRapFirmware heater number for M307 H (default: 1)")
      ->check(CLI::Range(0, 31));
  sub->add_flag("--kalico-pid", o.kalico_pid, "Kalico: write a PID designed from the thermal model instead of MPC");
  export_finite_option(sub, "--thermal-loop-delay", o.thermal_loop_delay, "s",
                       "Control loop delay in s for the PID design and RepRapFirmware's D (default 0.8: Klipper's "
                       "0.3 s sensor report plus half its 1 s derivative smoothing)");
  sub->add_flag("--no-pa", o.no_pa, "Leave pressure/linear advance alone");
  sub->add_flag("--no-shaper", o.no_shaper, "Leave input shaping alone");
  sub->add_flag("--write", o.write,
                "Apply the change: timestamped backup FILE.YYYYmmdd-HHMMSS.bak, then atomic replacement");
  sub->add_option("--gcode", o.gcode_out, "Also write the settings as G-code to this file (Marlin: M900/M593/M500)");
  sub->add_option("--orca-out", o.orca_out,
                  "Write an OrcaSlicer filament profile with adaptive pressure advance (the need at each identified "
                  "flow) to this file");
  sub->add_option("--orca-in", o.orca_in,
                  "OrcaSlicer filament profile to merge into (every other key kept byte for byte); default: a new "
                  "profile");
  sub->add_option("--orca-name", o.orca_name, "Name of a new OrcaSlicer profile");
  sub->add_option("--gcode-in", o.sliced_in,
                  "Sliced G-code (PrusaSlicer, OrcaSlicer or Cura ;TYPE: features) to give a per-feature advance");
  sub->add_option("--gcode-out", o.sliced_out, "Where the post-processed G-code goes (written atomically)");
  sub->add_option("--plot", o.plot_out,
                  "Draw the advance against flow (need, 95 % band, each exported model, design flow) to FILE.svg/.png");
  sub->add_option("--hysteresis", o.hysteresis,
                  "Relative change of the advance needed before the post-processor writes a new value (default 0.1)")
      ->check(CLI::Range(0.0, 0.99));
  add_output_options(sub, output);
  sub->footer(
      "Prints a unified diff of the configuration on stdout (a summary and the equivalent G-code on stderr);\n"
      "nothing is written without --write. Running it again after --write changes nothing.\n"
      "Examples:\n"
      "  tunekit export --firmware klipper --config printer.cfg --profile datasets/machines/sim.toml step.json "
      "shaper.json\n"
      "  tunekit export --firmware marlin --config Marlin/Configuration_adv.h --pa-k 0.045 --shaper-x zv:42:0.1 "
      "--write\n"
      "  tunekit export --firmware rrf --config sys/config.g step.json shaper.json rheo.json --json\n"
      "  tunekit export -f klipper -c printer.cfg --shaper-x mzv:52.4 --shaper-y ei:38.1:0.12 --no-pa\n"
      "  tunekit export -f marlin -c Marlin/Configuration.h thermal.json   # MPC; Klipper: a PID from the model\n"
      "  tunekit export -f kalico -c printer.cfg -p machine.toml sweep.json --orca-in PLA.json --orca-out "
      "PLA-tuned.json\n"
      "  tunekit export -f klipper -c printer.cfg -p machine.toml sweep.json --gcode-in part.gcode --gcode-out "
      "part-pa.gcode\n"
      "With two or more identified flow levels the advance is designed per flow (the stored melt volume, the\n"
      "integral of tau over flow): Klipper/Marlin/RepRapFirmware get K at the design flow and the flow range\n"
      "where it stays within 10 % of the need; Kalico its nonlinear model; OrcaSlicer the adaptive table.");
  return sub;
}

void register_export(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<ExportCommand>();
  add_export_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(commit_export(compute_export(cmd->options), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
