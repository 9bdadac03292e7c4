#pragma once
// One photo of printed tests -> calibrated widths: the one pipeline behind `tunekit linewidth`
// and the camera path of `tunekit calibrate`.
//
//   1. Scale. The candidates the caller knows of (a chessboard or ChArUco board in the photo, a
//      camera profile with a bed plane, a stated px/mm, the nominal width of the longest line)
//      are ranked by how directly they measure the bed plane in this very photo; the first one
//      that works is used and the choice is reported with its reason.
//   2. Features. measure_line_widths() finds every printed line (px); each gets a calibrated
//      profile in mm and one median (fitting::median).
//   3. The printed tests, where the caller describes them:
//      line test  straight lines along the bed's +X whose flow steps part-way; each line's widths
//                 along its commanded path, mapped to time (the step response);
//      ring test  a ring printed at constant speed whose set-point width is modulated
//                 sinusoidally with the angle travelled (Holtrup, Tuning liquefier dynamics, MSc
//                 thesis, University of Twente, 2019, section 4.3.3); gain and phase of the width
//                 against the set-point at the ring's frequency f = N v / (2 pi R).

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "tunekit/vision/camera_calibration.hpp"
#include "tunekit/vision/charuco.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"

namespace tunekit::vision {

/// What may give the photo's scale on the bed plane. Several may be given; see choose order below.
struct ScaleCandidates {
  std::optional<ChessboardSpec> chessboard;  ///< a chessboard lying on the bed in the photo
  std::optional<CharucoSpec> charuco;        ///< a ChArUco board lying on the bed in the photo
  std::optional<CameraProfile> camera;       ///< lens distortion (always removed) and maybe a bed plane
  double px_per_mm = 0;                      ///< stated scale (px/mm); 0: not given
  double nominal_width_mm = 0;               ///< the longest line has this width (mm); 0: not given
  bool rectify = false;                      ///< warp onto the bed plane (board or camera bed plane) first
};

/// The candidates in the order they are tried: a board measures the bed plane in this photo
/// (perspective included); a camera profile's bed plane was measured for this camera placement;
/// a stated px/mm is the user's word for it; a nominal width assumes the very thing a width
/// measurement is there to check, so it comes last.
enum class ScaleSource { none, board, camera_bed_plane, stated, nominal_width };

struct ScaleChoice {
  ScaleSource source = ScaleSource::none;
  double px_per_mm = 0;
  std::string name;                      ///< e.g. "ChArUco 5x7 x 10 mm (DICT_4X4_50), rectified"
  std::string reason;                    ///< why this one
  std::vector<std::string> passed_over;  ///< the other candidates given, with why they were not used
};

/// Image px (pixel centres at integers) -> bed mm, when the camera's placement is known.
struct BedPlacement {
  bool known = false;
  double x0_mm = 0, y1_mm = 0;  ///< bed x of the image's left edge, bed y of its top edge
};

/// One line of the line test: it starts at bed x `x0_mm` and runs along +X through `path`.
struct TestLine {
  double x0_mm = 0;
  std::vector<PathSegment> path;  ///< in print order
};

/// The line test: straight lines along the bed's +X, printed top to bottom in the photo.
struct LineTest {
  std::vector<TestLine> lines;  ///< in print order
  double filament_diameter_mm = 0;
  double layer_height_mm = 0;
};

/// The ring test. Set-point width at the angle theta travelled from the ring's start:
///   w_sp(theta) = w0 + a sin(N theta + phase)
/// tunekit's ring-print protocol modulates the extrusion by (1 + A sin(N theta)): a = A w0,
/// phase 0, constant along each of its `segments`. Holtrup's (2019) eq. 4.3 modulates the
/// feeder position: a = pi A N r_rod^2 / (h R), phase -90 deg (see ring_setpoint_amplitude_mm).
struct RingTest {
  int sines = 0;                     ///< N: sine periods per turn
  double speed_mm_s = 0;             ///< v: print speed
  double radius_mm = 0;              ///< R: commanded radius (mm); 0: the measured one
  double setpoint_width_mm = 0;      ///< w0
  double setpoint_amplitude_mm = 0;  ///< a
  /// a R instead of a (mm^2) where the amplitude follows the radius, as Holtrup's eq. 4.3
  /// (pi A N r_rod^2 / h) on a ring whose radius is measured; used when setpoint_amplitude_mm is 0.
  double setpoint_amplitude_mm2 = 0;
  double setpoint_phase_deg = 0;  ///< phase
  int segments = 0;               ///< set-point constant along each of this many segments; 0: smooth
  double start_deg = 0;           ///< view angle of theta = 0 (deg, counterclockwise from image +x)
  bool clockwise = false;         ///< the nozzle ran clockwise as seen in the photo
};

struct PhotoWidthsRequest {
  ScaleCandidates scale;
  LineWidthOptions detection;  ///< polarity, sample step, minimum length; the board's mask is added here
  std::optional<LineTest> line_test;
  std::optional<RingTest> ring_test;
  BedPlacement placement;  ///< the line test's lines are placed on their paths by it when known
};

/// One feature's profile in mm (samples as in the feature's px profile).
struct CalibratedLine {
  std::vector<double> s_mm, width_mm, confidence;  ///< width NaN where not measured
  double mean_mm = 0, std_mm = 0, median_mm = 0, length_mm = 0;
};

/// One line of the line test, along its commanded path.
struct LineTestResult {
  std::size_t feature = 0;        ///< index into PhotoWidths::features.lines
  std::vector<TimedWidth> rows;   ///< t from the path start
  double mean_width_mm = 0;       ///< over `rows`
  double median_width_mm = 0;     ///< over the whole measured line (all valid samples)
  bool placed_by_camera = false;  ///< placed by the camera's placement, else by the line's far end
};

struct RingResult {
  std::size_t feature = 0;
  /// At f: the width's relative modulation (amplitude over mean width) over the set-point's, and
  /// the width's phase less the set-point's (< 0: lag). Relative, so the photo's scale and the
  /// extrusion multiplier cancel: 1 for a liquefier that follows the set-point at f.
  double freq_hz = 0, gain = 0, phase_deg = 0;
  /// Standard errors and 95 % intervals of gain and phase: from the sine fit's residuals, their
  /// correlation along the ring included (the photo's noise; not a misplaced ring start, which
  /// shifts the phase by the start's angle error times N).
  double gain_stderr = std::numeric_limits<double>::quiet_NaN(),
         phase_stderr_deg = std::numeric_limits<double>::quiet_NaN();
  std::array<double, 2> gain_ci95{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()},
      phase_ci95_deg{std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  std::size_t samples = 0;
  double radius_mm = 0, measured_radius_mm = 0;
  cv::Point2d centre_px;
  double setpoint_amplitude_mm = 0, width_amplitude_mm = 0;
  double mean_width_mm = 0;      ///< the fitted mean width over the samples
  double skipped_start_rad = 0;  ///< samples before this angle travelled are left out (still filling)
  /// The samples fitted, by time from theta = 0: s = theta R, the set-point at each.
  std::vector<TimedWidth> rows;
};

struct PhotoWidths {
  cv::Mat measured;  ///< the grey image measured (undistorted, maybe rectified)
  ScaleChoice scale;
  std::vector<cv::Point> target_outline;  ///< the scale board in `measured` (px); empty: none
  /// Empty when the photo could not be measured (no board found, no line of the nominal width):
  /// then why; `features` holds what was found.
  std::string failure;
  LineWidthResult features;               ///< every feature, px (longest first)
  std::vector<CalibratedLine> lines;      ///< the same features in mm
  std::vector<LineTestResult> line_test;  ///< in print order
  std::optional<RingResult> ring;
  std::vector<std::string> warnings;
};

/// Measures a photo (any 1/3/4-channel image). `origin` names it in messages. Throws InputError
/// for contradictory requests (a rectification without a plane, a line test without a scale);
/// a photo that cannot be measured comes back with `failure` set.
PhotoWidths measure_photo_widths(const cv::Mat& photo, const PhotoWidthsRequest& request, const std::string& origin);

/// A ring: a closed feature, or an open one whose box is about square (a ring the detector cut
/// open where its end meets its start).
bool looks_like_ring(const MeasuredLine& feature);

/// Gain and phase of width against set-point for a ring feature already calibrated (exposed for
/// tests). Empty with a warning added when too few samples lie past the ring's start.
std::optional<RingResult> measure_ring(const MeasuredLine& feature, double px_per_mm, const RingTest& ring,
                                       std::vector<std::string>& warnings);

/// The ring's measurement as JSON, the same in every command that reports it: freq_hz, gain,
/// gain_stderr, gain_ci95, phase_deg, phase_stderr_deg, phase_ci95_deg, samples, radius_mm,
/// measured_radius_mm, mean_width_mm, setpoint_amplitude_mm, width_amplitude_mm.
nlohmann::json to_json(const RingResult& r);

}  // namespace tunekit::vision
