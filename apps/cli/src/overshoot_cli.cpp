// tunekit overshoot: the command line of the command (options bound straight into the library's
// option structs, so --help shows the library's defaults); the work is done by the
// calibration library's compute function.

#include "tunekit/cli/command.hpp"
#include "tunekit/cli/analysis_commands.hpp"
#include "tunekit/cli/commands.hpp"
#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/cli/option_binding.hpp"
#include "tunekit/calibration/analyses/overshoot_command.hpp"
#include "tunekit/calibration/presentation/report.hpp"
#include "tunekit/core/atomic_file.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/ident/overshoot.hpp"
#include "tunekit/protocols/runner.hpp"
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <map>
#include <memory>

namespace tunekit::cli {

using namespace calibration;

namespace {

struct OvershootCommand {
  OvershootOptions options;
  OutputOptions output;
};

}  // namespace

CLI::App* add_overshoot_command(CLI::App& app, OvershootOptions& o, OutputOptions& output) {
  auto* sub = app.add_subcommand(
      "overshoot", "Axis overshoot and settling at corners (axis-rectangle runs); grid of speeds and accelerations");
  sub->add_option("run", o.input,
                  "A run directory of 'tunekit run axis-rectangle' or a CSV (time in s); omit it for grid mode");
  sub->add_option("--band-mm", o.analysis.band_mm, "Settling band, +- mm around the settled position")
      ->capture_default_str();
  sub->add_option("--tail", o.analysis.tail_fraction, "Share of each pause taken as settled (drift reference)")
      ->capture_default_str();
  sub->add_option("--drift-order", o.analysis.drift_order,
                  "Accelerometer: order of the polynomial drift removed from each pause's integrated position (1-5)")
      ->check(CLI::Range(1, 5))
      ->capture_default_str();
  sub->add_option("--min-pause", o.analysis.min_pause_s, "Shortest rest that counts as a corner (s)")
      ->capture_default_str();
  sub->add_option("--min-move", o.analysis.min_move_mm, "Smallest move of an axis into a corner that is reported (mm)")
      ->capture_default_str();
  sub->add_option("-t,--time", o.time_column, "CSV: time column (s)")->capture_default_str();
  sub->add_option("--accel-x", o.accel_x, "CSV: measured x acceleration column (mm/s^2)")->capture_default_str();
  sub->add_option("--accel-y", o.accel_y, "CSV: measured y acceleration column (mm/s^2)")->capture_default_str();
  sub->add_option("--cmd-x", o.cmd_x, "CSV: commanded x acceleration column (mm/s^2)");
  sub->add_option("--cmd-y", o.cmd_y, "CSV: commanded y acceleration column (mm/s^2)");
  sub->add_option("--position-x", o.pos_x, "CSV: x position / encoder column (mm); instead of the accelerometer");
  sub->add_option("--position-y", o.pos_y, "CSV: y position / encoder column (mm)");
  sub->add_flag("--traces", o.traces, "Include each corner's deviation trace in the JSON");
  sub->add_option(
      "-p,--param", o.params,
      "Grid mode: axis-rectangle parameter NAME=V1,V2,... (speed_mm_s and accel_mm_s2 take lists; others one value)");
  sub->add_option("-m,--machine", o.run.machine, "Grid mode: 'sim' or a machine profile TOML")->capture_default_str();
  sub->add_option("--port", o.run.port, "Grid mode: the machine's port (see tunekit run)");
  sub->add_option("--sim", o.sim_options, "Grid mode: simulator option KEY=VALUE (repeatable), e.g. mode_x=40:0.05");
  sub->add_option("--tolerance-mm", o.tolerance_mm, "Grid mode: overshoot tolerance of the figure of merit (mm)")
      ->capture_default_str();
  sub->add_option("--shaper", o.shapers,
                  "Grid mode on the simulator: also run the grid with input shaping AXIS=TYPE:FREQ_HZ[:DAMPING] "
                  "(repeatable, e.g. x=zv:48) and compare shaping on/off");
  sub->add_option("--out", o.out_dir, "Grid mode: directory for the grid's runs, results.json and report.html");
  sub->add_option("--runs-root", o.run.runs_root, "Grid mode: default parent of --out")->capture_default_str();
  add_output_options(sub, output);
  sub->footer(
      "The overshoot is the largest excursion past the settled position after the commanded motion into a corner\n"
      "ends; the settling time runs from that end until the deviation stays within --band-mm. From an\n"
      "accelerometer, measured minus commanded acceleration is integrated twice per pause, with the drift\n"
      "removed against the pause's settled tail. The figure of merit of the grid is the normalized motion speed\n"
      "where the overshoot is within --tolerance-mm, else 0 (Hemminger, Improvements and Characterization of\n"
      "Error, Speed, and Capabilities in Low-Cost Additive Manufacturing Systems, MS thesis, UCLA, 2022).\n"
      "Examples:\n"
      "  tunekit run axis-rectangle --machine sim --run-dir runs/rect && tunekit overshoot runs/rect\n"
      "  tunekit overshoot encoder.csv --time t_s --position-x x_mm --band-mm 0.02\n"
      "  tunekit overshoot -p speed_mm_s=50,100,200 -p accel_mm_s2=1000,3000,6000 --machine sim --tolerance-mm 0.03 "
      "\\\n"
      "      --out runs/os-grid      # writes runs/os-grid/report.html with the grid map\n"
      "  tunekit overshoot -p accel_mm_s2=2000,5000,8000 --sim mode_x=48:0.08 --shaper x=zv:48 --shaper y=mzv:37 \\\n"
      "      --out runs/os-shaped    # the same grid with input shaping off and on\n"
      "Exit codes: 2 bad input (no corner found, missing columns), 3 machine failure in grid mode.");
  return sub;
}

void register_overshoot(CLI::App& app, CliContext& ctx) {
  auto cmd = std::make_shared<OvershootCommand>();
  add_overshoot_command(app, cmd->options, cmd->output)->callback([cmd, &ctx] {
    set_exit_code(
        report_outcome(compute_overshoot(cmd->options, ctx.verbosity > 0 ? &ctx.err : nullptr), cmd->output, ctx));
  });
}

}  // namespace tunekit::cli
