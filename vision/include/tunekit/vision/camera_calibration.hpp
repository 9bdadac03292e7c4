#pragma once
// Scale and distortion for the line-width measurement: chessboard detection, scale from a
// chessboard lying on the bed, perspective rectification of the bed plane, and camera
// calibration (intrinsics + distortion) from several chessboard images, stored as a camera
// profile (JSON).

#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace tunekit::vision {

/// A chessboard target: inner corners (cols x rows, e.g. a board of 10 x 7 squares has 9 x 6)
/// and the side of a square (mm).
struct ChessboardSpec {
  int cols = 0;
  int rows = 0;
  double square_mm = 0;
};

/// Parses "9x6" (inner corners). Throws InputError when malformed.
ChessboardSpec parse_chessboard_spec(const std::string& text, double square_mm);

struct ChessboardDetection {
  bool found = false;
  std::vector<cv::Point2f> corners;  ///< image px, row-major in board order
  cv::Matx33d img_to_mm;             ///< homography: image px -> board plane mm
  double px_per_mm = 0;              ///< scale at the board centre (sqrt of the local area ratio)
  double fit_rms_px = 0;             ///< RMS distance of the corners from the homography (px)
  std::vector<cv::Point> outline;    ///< polygon covering the whole board (one square beyond the corners)
};

/// Finds the chessboard (sub-pixel corners) in a grey image (any depth). found=false when absent.
ChessboardDetection detect_chessboard(const cv::Mat& gray, const ChessboardSpec& spec);

/// Image px -> board/bed mm local scale at image point p (px per mm).
double local_px_per_mm(const cv::Matx33d& img_to_mm, cv::Point2d p);

struct CameraProfile {
  cv::Size image_size;
  cv::Matx33d camera_matrix = cv::Matx33d::eye();
  std::vector<double> dist_coeffs;  ///< OpenCV order k1 k2 p1 p2 k3
  double rms_reprojection_px = 0;
  int images_used = 0;
  bool has_bed_plane = false;
  cv::Matx33d bed_img_to_mm = cv::Matx33d::eye();  ///< undistorted image px -> bed mm
  double px_per_mm = 0;                            ///< scale on the bed plane at the bed target's centre
  ChessboardSpec target;

  nlohmann::json to_json() const;
  static CameraProfile from_json(const nlohmann::json& j, const std::string& origin);
};

/// Calibrates from chessboard images (grey). Images where the board is not found are listed in
/// `skipped`. The first image with a board defines the bed plane (it must lie on the bed, seen
/// from the measuring pose). Throws InputError when fewer than 3 boards were found (FitError
/// when the calibration does not converge).
CameraProfile calibrate_camera(const std::vector<cv::Mat>& grays, const ChessboardSpec& spec,
                               std::vector<int>* skipped = nullptr);

/// A camera profile JSON file (as --save-camera writes it); InputError located at `path`.
CameraProfile load_camera_profile(const std::string& path);
/// The same of the file's bytes already read.
CameraProfile parse_camera_profile(std::string_view text, const std::string& path);

/// Removes lens distortion (no-op when the profile has none). Throws InputError when the image
/// size differs from the calibrated one.
cv::Mat undistort_image(const cv::Mat& gray, const CameraProfile& profile, const std::string& origin);

struct Rectified {
  cv::Mat image;  ///< bed-plane image, `px_per_mm` px per mm, axes along the target's
  double px_per_mm = 0;
  cv::Matx33d img_to_rect;  ///< source image px -> rectified px
};

/// Warps an image onto the bed plane given by `img_to_mm`, at `px_per_mm`. The output covers
/// the source image's footprint on the plane, limited to `max_pixels`.
Rectified rectify_to_plane(const cv::Mat& gray, const cv::Matx33d& img_to_mm, double px_per_mm,
                           double max_pixels = 40e6);

}  // namespace tunekit::vision
