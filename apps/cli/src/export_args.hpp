#pragma once
// `tunekit export`'s options (bound in cmd_export_options.cpp) and the command itself
// (cmd_export.cpp).

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "tunekit/cli/context.hpp"
#include "tunekit/fitting/fit_result.hpp"
#include "tunekit/protocols/firmware_export.hpp"

namespace tunekit::cli::export_cmd {

struct ExportArgs {
  std::string firmware;
  bool marlin_ft_live = false;  ///< the running Marlin reported fixed-time motion active (M493)
  std::string config;
  std::vector<std::string> results;
  std::string profile;
  double pa_k = fitting::kNaN;
  double pa_smooth = fitting::kNaN;
  double design_flow = fitting::kNaN;
  std::string shaper_x, shaper_y;
  std::string extruder = "extruder";
  int drive = 0;
  bool drive_given = false;
  bool no_pa = false;
  bool no_shaper = false;
  bool write = false;
  std::string gcode_out;
  std::string sliced_in, sliced_out;  // --gcode-in / --gcode-out (per-feature advance)
  double hysteresis = 0.10;
  std::string plot_out;  // --plot: the flow-dependent advance figure (SVG or PNG)
  std::string orca_in, orca_out, orca_name = "tunekit flow-dependent advance";
  OutputOptions output;
  const CLI::Option* pa_k_opt = nullptr;
  const CLI::Option* pa_smooth_opt = nullptr;
  const CLI::Option* design_flow_opt = nullptr;
};

/// tunekit export with these options; the exit code.
int run_export(const ExportArgs& a, CliContext& ctx);

/// An option given on the command line must be a finite number.
void require_finite_option(const CLI::Option* opt, double v, const char* unit);
/// --shaper-x/--shaper-y TYPE:FREQ[:ZETA].
protocols::ShaperSetting parse_shaper_arg(const std::string& arg, const std::string& axis);

}  // namespace tunekit::cli::export_cmd
