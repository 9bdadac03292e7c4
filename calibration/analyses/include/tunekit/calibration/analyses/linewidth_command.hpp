#pragma once
// tunekit linewidth as a function: calibrated width profiles of printed lines from photos.
// Scale comes from --px-per-mm, a camera profile, a chessboard or ChArUco board in the scene
// (optionally rectified onto the bed plane) or a line of known width. One line's profile can be
// mapped to time with the commanded speed (constant, the sine-modulated ring of Holtrup, Tuning
// liquefier dynamics, MSc thesis, University of Twente, 2019, eq. 4.2/4.3, or the extruding moves
// of a G-code file) and written as CSV for `tunekit freq` / `tunekit step`. With save_camera the
// photos calibrate a camera instead and its profile is written. The shape of a command is described
// in docs/cpp-api.md.

#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tunekit/calibration/results/envelope.hpp"
#include "tunekit/calibration/results/input_digest.hpp"
#include "tunekit/vision/camera_calibration.hpp"
#include "tunekit/vision/charuco.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/photo_widths.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"

namespace tunekit::calibration {

struct LinewidthOptions {
  std::vector<std::string> images;  ///< photos (or, with save_camera, chessboard calibration photos)
  /// Images whose header claims more pixels are refused before decoding (megapixels).
  double max_image_mp = static_cast<double>(vision::kDefaultMaxImagePixels) / 1e6;
  // Scale, one of: px_per_mm, camera (with a bed plane), chessboard or charuco, reference_width_mm.
  double px_per_mm = 0;                                       ///< image scale on the bed plane (px/mm); 0: not given
  std::string camera;                                         ///< camera profile JSON (lens distortion, bed plane)
  std::string chessboard;                                     ///< inner corners "COLSxROWS"
  double square_mm = 0;                                       ///< chessboard / ChArUco square side (mm)
  std::string charuco;                                        ///< ChArUco squares "SQUARESxSQUARES"
  double marker_mm = 0;                                       ///< ChArUco marker side (mm)
  std::string aruco_dict = vision::CharucoSpec{}.dictionary;  ///< OpenCV dictionary name
  double reference_width_mm = 0;                              ///< the longest line has this width (mm); 0: not given
  bool rectify = false;                                       ///< warp onto the bed plane first
  /// Polarity, profile sample spacing (px) and minimum line length (px); the scale target's
  /// exclusion mask is set per image by compute_linewidth().
  vision::LineWidthOptions detection;
  bool allow_edge = false;  ///< measure lines touching the frame edge instead of failing
  std::string overlay_dir;  ///< check images go here; empty: none
  std::string save_camera;  ///< non-empty: calibrate the camera and write its profile here
  // Mapping one line to time (profile_csv non-empty).
  std::string profile_csv;       ///< CSV written: time (s), s (mm), width (mm), setpoint_width (mm), confidence
  int line = 1;                  ///< which line (1 = longest)
  double speed_mm_s = 0;         ///< commanded print speed (mm/s)
  double setpoint_width_mm = 0;  ///< set-point width (mm); 0: the measured mean (or from the feed with gcode)
  int ring_sines = 0;            ///< ring print: sines per rotation N; 0: not a ring
  double ring_amplitude_mm = 0;  ///< ring print: feeder offset amplitude A (mm)
  double ring_radius_mm = 0;     ///< ring print: radius R (mm); 0: measured
  double rod_radius_mm = 0;      ///< ring print: feed rod radius (mm)
  double layer_height_mm = 0;    ///< ring print, or the set-point from a G-code's feed (mm)
  double ring_flow_amplitude =
      0;                  ///< ring print: relative extrusion modulation A of (1 + A sin(N theta)); 0: Holtrup's feeder
  int ring_segments = 0;  ///< ring print: straight segments per turn (set-point constant along each); 0: smooth
  double ring_start_deg = 0;    ///< ring print: theta = 0 in the photo (deg, counterclockwise from +x)
  bool ring_clockwise = false;  ///< ring print: the nozzle ran clockwise in the photo
  std::string gcode;            ///< G-code that printed the line; empty: none
  /// With gcode: offset_mm (NaN: profile centred on the path), reversed, filament_diameter_mm
  /// (mm); its layer_height_mm and setpoint_width_mm are filled from the members above.
  vision::PathMapping path;
};

/// One measured photo.
struct LinewidthImage {
  std::string path;
  double px_per_mm = 0;                       ///< the scale used (px/mm)
  vision::ScaleChoice scale;                  ///< where the scale came from and why
  vision::LineWidthResult result;             ///< every line's profile in px
  std::vector<vision::CalibratedLine> lines;  ///< the same lines in mm
  std::optional<vision::RingResult> ring;     ///< with ring_sines: gain and phase of the ring (the longest ring)
};

struct LinewidthOutcome {
  LinewidthOptions options;
  std::vector<InputDigest> inputs;     ///< camera profile, images, G-code, in the order read
  std::vector<LinewidthImage> images;  ///< empty with save_camera
  /// The "profile_csv" results object of the written --profile-csv (mapping kind, rows, duration in s,
  /// set-point width in mm, ...); empty without profile_csv.
  nlohmann::json profile_csv;
  std::optional<vision::CameraProfile> camera;  ///< the calibrated profile (save_camera), written there
  std::vector<std::string> warnings;
};

/// Measures the photos, writes the overlays and the profile CSV (or calibrates and writes the camera
/// profile). A failed overlay write is reported on `err` at once ("tunekit: warning: ...") so it
/// cannot hide the measurement's own error. InputError (exit 2) for bad options, unreadable images,
/// a missing scale target or a line touching the frame edge; FitError (exit 1) when nothing is measured.
LinewidthOutcome compute_linewidth(const LinewidthOptions& options, std::ostream& err);

Envelope to_envelope(const LinewidthOutcome& outcome);
void print_text(const LinewidthOutcome& outcome, std::ostream& os);

}  // namespace tunekit::calibration
