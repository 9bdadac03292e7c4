// tunekit export's command line: its options bound to ExportArgs, the help text, and the
// parsing of option values (the command itself is cmd_export.cpp).
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "tunekit/cli/commands.hpp"
#include "tunekit/cli/envelope.hpp"
#include "tunekit/cli/plots.hpp"
#include "tunekit/cli/results_json.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/ident/csv.hpp"
#include "tunekit/ident/flow_advance.hpp"
#include "tunekit/ident/pressure_advance.hpp"
#include "tunekit/protocols/atomic_file.hpp"
#include "tunekit/protocols/config_edit.hpp"
#include "tunekit/protocols/firmware_export.hpp"
#include "tunekit/protocols/firmware_limits.hpp"
#include "tunekit/protocols/gcode_advance.hpp"
#include "tunekit/protocols/orca_profile.hpp"
#include "tunekit/protocols/machine_profile.hpp"


#include "export_args.hpp"

namespace tunekit::cli {
namespace export_cmd {

/// An option given on the command line must be a finite number.
void require_finite_option(const CLI::Option* opt, double v, const char* unit) {
  if (opt && opt->count() > 0 && !std::isfinite(v))
    throw InputError(fmt::format("{} must be a finite number ({}), not '{}'", opt->get_name(), unit, opt->as<std::string>()));
}

protocols::ShaperSetting parse_shaper_arg(const std::string& arg, const std::string& axis) {
  // TYPE:FREQ[:ZETA]
  std::vector<std::string> parts;
  std::stringstream ss(arg);
  std::string p;
  while (std::getline(ss, p, ':')) parts.push_back(p);
  if (parts.size() < 2 || parts.size() > 3 || parts[0].empty())
    throw InputError(fmt::format("--shaper-{} takes TYPE:FREQ[:ZETA] (for example mzv:45.2:0.1), not '{}'", axis, arg));
  protocols::ShaperSetting s;
  s.type = parts[0];
  try {
    std::size_t used = 0;
    s.freq_hz = std::stod(parts[1], &used);
    if (used != parts[1].size()) throw std::invalid_argument("trailing");
    if (parts.size() == 3) {
      s.damping = std::stod(parts[2], &used);
      if (used != parts[2].size()) throw std::invalid_argument("trailing");
    }
  } catch (const std::logic_error&) {
    throw InputError(fmt::format("--shaper-{}: '{}' has a frequency or damping that is not a number", axis, arg));
  }
  return s;
}

}  // namespace export_cmd

void register_export(CLI::App& app, CliContext& ctx) {
  using export_cmd::ExportArgs;
  auto args = std::make_shared<ExportArgs>();
  auto* sub = app.add_subcommand(
      "export", "Write pressure advance and input shaping into firmware configuration (diff preview; --write applies)");
  sub->add_option("results", args->results,
                  "JSON results of 'tunekit step', 'freq', 'shaper' and/or 'rheo' (any number, any order)");
  sub->add_option("-f,--firmware", args->firmware,
                  "Firmware dialect: klipper, kalico (nonlinear advance from two or more flow levels), marlin or rrf")
      ->required();
  sub->add_option("-c,--config", args->config,
                  "Configuration file to edit: printer.cfg (klipper), Configuration_adv.h (marlin), config.g (rrf)")
      ->required();
  sub->add_option("-p,--profile", args->profile,
                  "Machine profile TOML (filament diameter mm, line width/height mm, print speed mm/s, print and "
                  "extruder acceleration mm/s^2) for the smoothing time");
  args->pa_k_opt = sub->add_option("--pa-k", args->pa_k, "Advance K in s (mm of filament per mm/s), instead of the results");
  args->pa_smooth_opt = sub->add_option("--pa-smooth", args->pa_smooth,
                  "Smoothing time in s (Klipper pressure_advance_smooth_time, Marlin ADVANCE_TAU), instead of the design");
  args->design_flow_opt = sub->add_option("--design-flow", args->design_flow,
                  "Volumetric flow in mm^3/s the single advance value is designed for (default: print speed x line "
                  "cross-section)");
  sub->add_option("--shaper-x", args->shaper_x, "X shaper TYPE:FREQ[:ZETA] (frequency in Hz, damping ratio 0-1)");
  sub->add_option("--shaper-y", args->shaper_y, "Y shaper TYPE:FREQ[:ZETA] (frequency in Hz, damping ratio 0-1)");
  sub->add_option("--extruder", args->extruder,
                  "Extruder: a Klipper section name (default: extruder), or a number N: Klipper [extruderN], Marlin's "
                  "Nth ADVANCE_K entry (M900 TN), RepRapFirmware drive N");
  sub->add_option("--drive", args->drive, "RepRapFirmware extruder drive number for M572 D (default: 0)")
      ->each([args](const std::string&) { args->drive_given = true; });
  sub->add_flag("--marlin-ft-motion", args->marlin_ft_live,
                "The running Marlin reports fixed-time motion enabled (M493): shapers among FT_MOTION's, runtime "
                "G-code M493 instead of M593/M900 (tunekit calibrate sets it from the printer's answer)");
  sub->add_flag("--no-pa", args->no_pa, "Leave pressure/linear advance alone");
  sub->add_flag("--no-shaper", args->no_shaper, "Leave input shaping alone");
  sub->add_flag("--write", args->write,
                "Apply the change: timestamped backup FILE.YYYYmmdd-HHMMSS.bak, then atomic replacement");
  sub->add_option("--gcode", args->gcode_out, "Also write the settings as G-code to this file (Marlin: M900/M593/M500)");
  sub->add_option("--orca-out", args->orca_out,
                  "Write an OrcaSlicer filament profile with adaptive pressure advance (the need at each identified "
                  "flow) to this file");
  sub->add_option("--orca-in", args->orca_in,
                  "OrcaSlicer filament profile to merge into (every other key kept byte for byte); default: a new "
                  "profile");
  sub->add_option("--orca-name", args->orca_name, "Name of a new OrcaSlicer profile");
  sub->add_option("--gcode-in", args->sliced_in,
                  "Sliced G-code (PrusaSlicer, OrcaSlicer or Cura ;TYPE: features) to give a per-feature advance");
  sub->add_option("--gcode-out", args->sliced_out, "Where the post-processed G-code goes (written atomically)");
  sub->add_option("--plot", args->plot_out,
                  "Draw the advance against flow (need, 95 % band, each exported model, design flow) to FILE.svg/.png");
  sub->add_option("--hysteresis", args->hysteresis,
                  "Relative change of the advance needed before the post-processor writes a new value (default 0.1)")
      ->check(CLI::Range(0.0, 0.99));
  add_output_options(sub, args->output);
  sub->footer(
      "Prints a unified diff of the configuration on stdout (a summary and the equivalent G-code on stderr);\n"
      "nothing is written without --write. Running it again after --write changes nothing.\n"
      "Examples:\n"
      "  tunekit export --firmware klipper --config printer.cfg --profile datasets/machines/sim.toml step.json shaper.json\n"
      "  tunekit export --firmware marlin --config Marlin/Configuration_adv.h --pa-k 0.045 --shaper-x zv:42:0.1 --write\n"
      "  tunekit export --firmware rrf --config sys/config.g step.json shaper.json rheo.json --json\n"
      "  tunekit export -f klipper -c printer.cfg --shaper-x mzv:52.4 --shaper-y ei:38.1:0.12 --no-pa\n"
      "  tunekit export -f kalico -c printer.cfg -p machine.toml sweep.json --orca-in PLA.json --orca-out PLA-tuned.json\n"
      "  tunekit export -f klipper -c printer.cfg -p machine.toml sweep.json --gcode-in part.gcode --gcode-out part-pa.gcode\n"
      "With two or more identified flow levels the advance is designed per flow (the stored melt volume, the\n"
      "integral of tau over flow): Klipper/Marlin/RepRapFirmware get K at the design flow and the flow range\n"
      "where it stays within 10 % of the need; Kalico its nonlinear model; OrcaSlicer the adaptive table.");
  sub->callback([args, &ctx] { set_exit_code(export_cmd::run_export(*args, ctx)); });
}

}  // namespace tunekit::cli
