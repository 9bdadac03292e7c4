#pragma once
// The liquefier paths of `tunekit calibrate`:
//   load-cell  the feed is stepped and chirped while a load cell (or Klipper's load_cell) is read;
//   camera     a line test (flow steps along straight lines) and a ring test (flow modulated around
//              a ring) are printed and photographed; the widths along the lines are the step
//              response (tau, theta), the width around the ring gives gain and phase at the ring's
//              frequency (Holtrup, Tuning liquefier dynamics, MSc thesis, University of Twente,
//              2019, ch. 4.3);
//   auto       load-cell when the profile has one, else camera.
// The photo comes from the simulated printer's camera (--camera sim), a file (--photo), a camera
// device through OpenCV's videoio (--camera-device, several frames averaged), or a file path
// typed at a terminal.

#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/guided/calibrate_command.hpp"
#include "tunekit/ident/ring_prediction.hpp"
#include "tunekit/calibration/results/context.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/calibration/results/plot_data.hpp"
#include "tunekit/machine/machine_profile.hpp"
#include "tunekit/protocols/runner.hpp"
#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/vision/photo_widths.hpp"

namespace tunekit::calibration {

enum class LiquefierPath { load_cell, camera };

/// --liquefier auto|load-cell|camera against the profile's sensors (InputError with the
/// profile path when a load cell is asked for and there is none).
LiquefierPath choose_liquefier_path(const std::string& choice, const machine::MachineProfile& profile,
                                    const std::string& profile_path);

/// Checked before anything is printed: a photo source must exist (InputError, exit 2, otherwise).
void check_photo_source(const LiquefierCameraArgs& a, bool sim_machine, bool can_prompt);

/// The printed tests of the camera path: sub-directory, protocol and parameter overrides.
struct CameraTest {
  std::string name;
  std::string protocol;
  std::map<std::string, double> params;
};
/// The line test's lead-in is as long as the profile's X travel takes (up to 90 mm; see line_lead_mm).
std::vector<CameraTest> camera_tests(const machine::MachineProfile& profile);

using ident::RingPrediction;

struct CameraAnalysis {                    // declared in calibration_pipeline.hpp
  std::string photo;                       ///< the photo used (in the run directory)
  std::string overlay;                     ///< the photo with the measured edges (PNG, in the run directory)
  std::string width_csv;                   ///< time, setpoint width, width of the line test (for `tunekit step`)
  std::string feed_track_csv;              ///< the line test's commanded feed in the record's time, beside it
  InputFile width_record;                  ///< width_csv as written: the step analysis takes it from memory
  InputFile feed_track;                    ///< feed_track_csv as written, likewise
  InputDigest photo_input;                 ///< the photo's digest, of the bytes read (or written)
  nlohmann::json results;                  ///< lines, ring (gain and phase), warnings, as results.json holds them
  std::optional<vision::RingResult> ring;  ///< the ring's gain and phase, when the photo shows it
  std::optional<RingPrediction> ring_prediction;  ///< set by add_ring_prediction
  std::vector<std::string> warnings;              ///< the photo measurement's
  LinewidthPlot linewidth_plot;                   ///< the line test's first line (plotdata.json "linewidth")
};

/// Obtains the photo, measures the lines and the ring and writes the width record. InputError
/// (exit 2) when the photo shows no printed line; MachineError (exit 3) when a camera cannot
/// be opened. `runs` holds the camera_tests() runs by name.
CameraAnalysis analyze_camera_prints(const std::string& run_dir, const LiquefierCameraArgs& a,
                                     const machine::MachineProfile& profile,
                                     const std::map<std::string, protocols::RunResult>& runs,
                                     const std::shared_ptr<sim::SimPrintBed>& bed, bool can_prompt, CliContext& ctx);

using ident::RingModel;

/// The ring's gain and phase, added to the camera analysis once tau and theta are known from
/// the lines (the model's prediction at the ring frequency is reported beside the measurement).
void add_ring_prediction(CameraAnalysis& camera, const RingModel& model);

}  // namespace tunekit::calibration
