#pragma once
// tunekit calibrate as a function: the technician's one command. Plans the experiments for the
// machine profile and firmware, checks every one against the machine's limits before anything is
// sent, runs them, identifies the models with the same functions (and defaults) the single
// commands use, designs pressure advance and input shaping, previews (or writes) the firmware
// configuration change and writes a run directory with results.json, plotdata.json and
// report.html. The stages, and run_calibrate() that runs them, are in calibration_pipeline.hpp.

#include <string>
#include <vector>

#include "tunekit/calibration/context.hpp"

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
  std::string firmware = "klipper";
  std::string config;
  bool write = false;
  bool skip_liquefier = false;
  bool skip_axes = false;
  /// Leave the heaters at the experiments' temperatures at the end (protocols::RunOptions::keep_heaters);
  /// by default every experiment that heated turns them off when it ends.
  bool keep_heaters = false;
  std::vector<std::string> sim_options;
  std::string liquefier = "auto";  // auto, load-cell, camera
  LiquefierCameraArgs camera;
  OutputOptions output;
};

}  // namespace tunekit::calibration
