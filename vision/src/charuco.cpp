#include "tunekit/vision/charuco.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>

#ifdef TUNEKIT_HAVE_ARUCO
#include <opencv2/aruco/charuco.hpp>
#endif

#include "tunekit/core/error.hpp"

namespace tunekit::vision {
namespace {

#ifdef TUNEKIT_HAVE_ARUCO
const std::map<std::string, cv::aruco::PREDEFINED_DICTIONARY_NAME>& charuco_dictionaries() {
  static const std::map<std::string, cv::aruco::PREDEFINED_DICTIONARY_NAME> m = {
      {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
      {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
      {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
      {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
      {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
      {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
      {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
      {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
      {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
      {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
      {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
      {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
      {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
      {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
      {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
      {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL}};
  return m;
}
#endif

cv::Point2d charuco_apply(const cv::Matx33d& H, cv::Point2d p) {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

}  // namespace

bool charuco_available() {
#ifdef TUNEKIT_HAVE_ARUCO
  return true;
#else
  return false;
#endif
}

CharucoSpec parse_charuco_spec(const std::string& text, double square_mm, double marker_mm,
                               const std::string& dictionary) {
  CharucoSpec s;
  char x = 0;
  int a = 0, b = 0;
  char tail = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &a, &x, &b, &tail) != 3 || (x != 'x' && x != 'X'))
    throw InputError(fmt::format("ChArUco board '{}' is not SQUARESxSQUARES (e.g. 5x7)", text));
  if (a < 3 || b < 3 || a > 100 || b > 100)
    throw InputError(fmt::format("ChArUco board '{}': 3..100 squares each way", text));
  if (!(square_mm > 0)) throw InputError("ChArUco square size must be > 0 mm (--square-mm)");
  if (!(marker_mm > 0 && marker_mm < square_mm))
    throw InputError("ChArUco marker size must be > 0 and smaller than the square (--marker-mm)");
  s.squares_x = a;
  s.squares_y = b;
  s.square_mm = square_mm;
  s.marker_mm = marker_mm;
  s.dictionary = dictionary.empty() ? "DICT_4X4_50" : dictionary;
#ifdef TUNEKIT_HAVE_ARUCO
  if (!charuco_dictionaries().count(s.dictionary))
    throw InputError(
        fmt::format("unknown ArUco dictionary '{}' (e.g. DICT_4X4_50, DICT_5X5_100, DICT_6X6_250)", s.dictionary));
  const int markers = (a * b) / 2;
  const auto dict = cv::aruco::getPredefinedDictionary(charuco_dictionaries().at(s.dictionary));
  if (dict->bytesList.rows < markers)
    throw InputError(fmt::format("a {}x{} ChArUco board needs {} markers; {} has {}", a, b, markers, s.dictionary,
                                 dict->bytesList.rows));
#endif
  return s;
}

ChessboardDetection detect_charuco(const cv::Mat& gray, const CharucoSpec& spec) {
  ChessboardDetection det;
#ifndef TUNEKIT_HAVE_ARUCO
  (void)gray;
  (void)spec;
  throw InputError(
      "ChArUco boards need OpenCV's aruco module, which this build was made without "
      "(Debian: libopencv-contrib-dev); use a chessboard (--chessboard)");
#else
  cv::Mat u8;
  if (gray.depth() == CV_16U) gray.convertTo(u8, CV_8U, 1.0 / 257.0);
  else u8 = gray;
  const auto dict = cv::aruco::getPredefinedDictionary(charuco_dictionaries().at(spec.dictionary));
  // Board units are mm, so corner positions come out in mm.
  const auto board = cv::aruco::CharucoBoard::create(spec.squares_x, spec.squares_y, static_cast<float>(spec.square_mm),
                                                     static_cast<float>(spec.marker_mm), dict);
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2f>> marker_corners;
  cv::aruco::detectMarkers(u8, dict, marker_corners, ids);
  if (ids.size() < 2) return det;
  std::vector<cv::Point2f> corners;
  std::vector<int> corner_ids;
  cv::aruco::interpolateCornersCharuco(marker_corners, ids, u8, board, corners, corner_ids);
  if (corners.size() < 6) return det;
  // Board-plane positions (mm) of the visible corners, origin at the first inner corner.
  std::vector<cv::Point2f> plane;
  const cv::Point3f origin = board->chessboardCorners.front();
  for (int id : corner_ids) {
    const cv::Point3f q = board->chessboardCorners[static_cast<std::size_t>(id)];
    plane.emplace_back(q.x - origin.x, q.y - origin.y);
  }
  const cv::Mat H = cv::findHomography(corners, plane, 0);
  if (H.empty()) return det;
  det.img_to_mm = cv::Matx33d(H);
  const cv::Matx33d inv = det.img_to_mm.inv();
  double ss = 0;
  cv::Point2d centre(0, 0);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const cv::Point2d p = charuco_apply(inv, plane[i]);
    ss += (p.x - corners[i].x) * (p.x - corners[i].x) + (p.y - corners[i].y) * (p.y - corners[i].y);
    centre += cv::Point2d(corners[i]);
  }
  det.fit_rms_px = std::sqrt(ss / static_cast<double>(corners.size()));
  // Corners on one line give no plane: refuse them like a board that is not there.
  if (!std::isfinite(det.fit_rms_px) || cv::determinant(det.img_to_mm) == 0) return det;
  centre *= 1.0 / static_cast<double>(corners.size());
  det.found = true;
  det.corners = corners;
  det.px_per_mm = local_px_per_mm(det.img_to_mm, centre);
  // The outline covers the whole board (one square beyond the outer inner corners).
  const double s = spec.square_mm;
  const double xe = (spec.squares_x - 2) * s, ye = (spec.squares_y - 2) * s;
  for (const cv::Point2d q : {cv::Point2d(-1.1 * s, -1.1 * s), cv::Point2d(xe + 1.1 * s, -1.1 * s),
                              cv::Point2d(xe + 1.1 * s, ye + 1.1 * s), cv::Point2d(-1.1 * s, ye + 1.1 * s)}) {
    const cv::Point2d p = charuco_apply(inv, q);
    det.outline.emplace_back(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
  }
  return det;
#endif
}

}  // namespace tunekit::vision
