#pragma once
// tunekit calibrate as a function: the technician's one command. Plans the experiments for the
// machine profile and firmware, checks every one against the machine's limits before anything is
// sent, runs them, identifies the models with the same functions (and defaults) the single
// commands use, designs pressure advance and input shaping, previews (or writes) the firmware
// configuration change and writes a run directory with results.json, plotdata.json and
// report.html. The stages, and run_calibrate() that runs them, are in calibration_pipeline.hpp.

#include <string>
#include <vector>

#include "tunekit/calibration/results/context.hpp"

namespace tunekit::calibration {

/// Where calibrate's camera path gets its photo of the printed tests.
struct LiquefierCameraArgs {
  std::string camera;         ///< "sim": the simulated printer's camera
  std::string photo;          ///< a photo file of the printed tests
  std::string camera_device;  ///< e.g. /dev/video0
  double px_per_mm = 0;       ///< image scale of a photo / camera on the bed (px/mm)
  int frames = 8;             ///< camera frames averaged
  double settle_s = 2.0;      ///< camera focus / exposure settle time before the frames
};

/// What a technician chooses for `tunekit calibrate`.
struct CalibrateArgs {
  std::string machine = "sim";
  std::string profile;
  std::string port;
  std::string out_dir;
  /// The configuration dialect to update, and the firmware the simulator runs: klipper, kalico,
  /// marlin or rrf; empty: the --profile's [machine] firmware (prusa: marlin), else klipper.
  std::string firmware;
  std::string config;
  bool write = false;
  bool skip_liquefier = false;
  bool skip_axes = false;
  /// --thermal: first of all, the hot end's thermal experiment (heater-identify, from rest) and
  /// its model (tunekit thermal) with `heater_power_w` given as its P (W).
  bool thermal = false;
  double heater_power_w = 40.0;
  /// Leave the heaters at the experiments' temperatures at the end (protocols::RunOptions::keep_heaters);
  /// by default every experiment that heated turns them off when it ends.
  bool keep_heaters = false;
  std::vector<std::string> sim_options;
  std::string liquefier = "auto";  // auto, load-cell, camera
  LiquefierCameraArgs camera;
  /// Protocol parameters, "EXPERIMENT.NAME=VALUE" or "PROTOCOL.NAME=VALUE" (axis-x.freq_end_hz=80,
  /// axis-sweep.accel_per_hz=40, liquefier-chirp.segment_s=0.05), value in the unit its name
  /// carries; checked with the protocol's other parameters before anything is sent.
  std::vector<std::string> params;
  /// Plan and check every experiment against the limits, print the plan (each experiment's
  /// protocol, parameters and machine time) and stop: nothing is sent, no run directory is made.
  bool dry_run = false;
  /// Machine time (s) the experiments may take together; 0: the design's own. Below it, the
  /// sweeps run faster, the holds and the chirp shorter, by one factor; the plan says what the
  /// intervals then cost. InputError when even the shortest design exceeds it.
  double budget_s = 0;
  /// Sensors the firmware configuration given as --profile does not list but the machine has
  /// ("accelerometer", "load_cell", "camera"): `tunekit profile --sensor`'s. A TOML profile lists
  /// its own ([sensors]).
  std::vector<std::string> sensors;
  OutputOptions output;
};

/// The firmware calibrate designs for (and simulates): `requested` when given, else the
/// profile's [machine] firmware as an export dialect (prusa: marlin), else klipper.
std::string resolved_calibrate_firmware(const std::string& requested, const std::string& profile_firmware);

}  // namespace tunekit::calibration
