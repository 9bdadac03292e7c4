#pragma once
// ChArUco boards (a chessboard whose white squares carry ArUco markers; Garrido-Jurado et al.,
// "Automatic generation and detection of highly reliable fiducial markers under occlusion",
// Pattern Recognition, 2014) as the scale target of the line-width measurement. Unlike a plain
// chessboard, a ChArUco board is found when only part of it is in the picture or some squares
// are covered by a printed part. Available when the installed OpenCV has the aruco module
// (Debian: libopencv-contrib-dev); otherwise detection refuses with a clear error.

#include <string>

#include <opencv2/core.hpp>

#include "tunekit/vision/camera_calibration.hpp"

namespace tunekit::vision {

/// A ChArUco board: squares_x x squares_y squares of square_mm, markers of marker_mm, from an
/// ArUco dictionary by OpenCV name (DICT_4X4_50, DICT_5X5_100, DICT_6X6_250, ...).
struct CharucoSpec {
  int squares_x = 0;
  int squares_y = 0;
  double square_mm = 0;
  double marker_mm = 0;
  std::string dictionary = "DICT_4X4_50";
};

/// Parses "5x7" (squares, not inner corners). InputError for a malformed text, sizes out of
/// range, a marker not smaller than its square, or an unknown dictionary.
CharucoSpec parse_charuco_spec(const std::string& text, double square_mm, double marker_mm,
                               const std::string& dictionary);

/// True when this build can detect ChArUco boards.
bool charuco_available();

/// Finds the board's inner corners that are visible (at least 6, not all on one line) in a grey
/// image (any depth); `corners` are the visible ones and `img_to_mm` maps the image onto the
/// board plane with the origin at the first inner corner, as for a chessboard. found=false when
/// absent. InputError when this build has no ChArUco support.
ChessboardDetection detect_charuco(const cv::Mat& gray, const CharucoSpec& spec);

}  // namespace tunekit::vision
