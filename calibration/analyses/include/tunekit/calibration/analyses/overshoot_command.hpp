#pragma once
// tunekit overshoot as a function: axis overshoot and settling at the corners of the axis-rectangle
// protocol (Hemminger, Improvements and Characterization of Error, Speed, and Capabilities in
// Low-Cost Additive Manufacturing Systems, MS thesis, UCLA, 2022) from a run directory or a CSV;
// or a grid that runs the protocol over lists of speeds and accelerations (on the simulator
// optionally with input shaping off and on) and maps overshoot, completion time and the thesis's
// figure of merit, writing the runs, results.json, plotdata.json and report.html. The shape of a
// command is described in docs/cpp-api.md.

#include <cstddef>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/ident/overshoot.hpp"
#include "tunekit/protocols/runner.hpp"

namespace tunekit::calibration {

struct OvershootOptions {
  std::string input;                                     ///< run directory or CSV to analyze; empty: grid mode
  std::string time_column = "time";                      ///< CSV: time column (s)
  std::string accel_x = "accel_x", accel_y = "accel_y";  ///< CSV: measured acceleration (mm/s^2)
  std::string cmd_x, cmd_y;                              ///< CSV: commanded acceleration columns (mm/s^2)
  std::string pos_x, pos_y;          ///< CSV: encoder / position columns (mm), instead of the accelerometer
  ident::OvershootOptions analysis;  ///< settling band (mm), tail share, pause and move thresholds, drift order
  bool traces = false;               ///< include each corner's deviation trace in the JSON
  // Grid mode.
  std::vector<std::string> params;  ///< axis-rectangle parameters NAME=V1,V2,... (lists for speed and accel)
  /// machine ("sim" or a profile), port and runs_root of every grid run; the protocol,
  /// parameters and run directory are set per grid point.
  protocols::RunOptions run;
  /// Simulator options KEY=VALUE (sim::SimConfig::from_options), with machine "sim".
  std::vector<std::string> sim_options;
  std::string out_dir;               ///< the grid's directory; empty: <runs_root>/overshoot-grid
  double tolerance_mm = 0.05;        ///< overshoot tolerance of the figure of merit (mm)
  std::vector<std::string> shapers;  ///< on the simulator: AXIS=TYPE:FREQ_HZ[:DAMPING], grid run again with them
};

/// One grid point.
struct OvershootGridCell {
  double speed_mm_s = 0, accel_mm_s2 = 0;
  double overshoot_mm = 0;       ///< mean over corners, worst axis (mm)
  double settling_time_s = 0;    ///< mean over corners, worst axis (s)
  double completion_time_s = 0;  ///< summed duration of the commanded motions (s)
  double figure_of_merit = 0;    ///< normalized speed within tolerance, else 0
  std::string run_dir;           ///< the point's run, relative to the grid's directory
  bool input_shaping = false;
};

struct OvershootGrid {
  std::string out_dir;                               ///< where the runs, results.json and report are
  std::map<std::string, std::vector<double>> lists;  ///< the parameter lists run
  std::vector<OvershootGridCell> cells;
  double mean_completion_time_s = 0;
  std::optional<std::size_t> best;         ///< index of the fastest unshaped point within tolerance
  std::optional<std::size_t> best_shaped;  ///< the same with input shaping
  std::string report;                      ///< path of the written report.html
};

struct OvershootOutcome {
  OvershootOptions options;
  std::vector<InputDigest> inputs;                   ///< the analyzed files
  std::optional<ident::OvershootAnalysis> analysis;  ///< analyze mode
  std::optional<OvershootGrid> grid;                 ///< grid mode
  std::vector<std::string> warnings;
};

/// Analyzes the run or CSV, or runs the grid (writing its directory). `progress`, when given,
/// gets a line per grid point. InputError (exit 2) for bad input, MachineError (exit 3) when a
/// machine fails in grid mode.
OvershootOutcome compute_overshoot(const OvershootOptions& options, std::ostream* progress = nullptr);

Envelope to_envelope(const OvershootOutcome& outcome);
void print_text(const OvershootOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
