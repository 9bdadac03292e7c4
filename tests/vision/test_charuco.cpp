// ChArUco boards as the scale target: a rendered board seen at a known scale and in
// perspective, also partly covered, gives the scale; without the aruco module the refusal is
// one clear error.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#ifdef TUNEKIT_TEST_HAVE_ARUCO
#include <opencv2/aruco/charuco.hpp>
#endif

#include "tunekit/core/error.hpp"
#include "tunekit/vision/charuco.hpp"

using namespace tunekit;

TEST_CASE("ChArUco board specs are parsed and checked") {
  const auto s = vision::parse_charuco_spec("5x7", 20, 15, "DICT_4X4_50");
  CHECK(s.squares_x == 5);
  CHECK(s.squares_y == 7);
  CHECK_THROWS_AS(vision::parse_charuco_spec("5by7", 20, 15, "DICT_4X4_50"), InputError);
  CHECK_THROWS_AS(vision::parse_charuco_spec("5x7", 20, 25, "DICT_4X4_50"), InputError);
  if (vision::charuco_available())
    CHECK_THROWS_WITH(vision::parse_charuco_spec("5x7", 20, 15, "DICT_9X9_1"),
                      Catch::Contains("unknown ArUco dictionary"));
}

TEST_CASE("a ChArUco board in perspective and partly covered gives the scale at its centre") {
  if (!vision::charuco_available()) {
    CHECK_THROWS_WITH(vision::detect_charuco(cv::Mat(100, 100, CV_8U, cv::Scalar(255)),
                                             vision::parse_charuco_spec("5x7", 20, 15, "")),
                      Catch::Contains("libopencv-contrib-dev"));
    return;
  }
  // The board drawn at 10 px per mm (5 x 7 squares of 20 mm = 1000 x 1400 px plus margin).
  cv::Mat board_img;
  {
#ifdef TUNEKIT_TEST_HAVE_ARUCO
    const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
    const auto board = cv::aruco::CharucoBoard::create(5, 7, 20.f, 15.f, dict);
    board->draw(cv::Size(1000, 1400), board_img, 0, 1);
#endif
  }
  REQUIRE(!board_img.empty());
  cv::Mat canvas(1800, 1600, CV_8U, cv::Scalar(255));
  board_img.copyTo(canvas(cv::Rect(300, 200, 1000, 1400)));
  // Cover one corner of the board (a printed part lying on it).
  cv::rectangle(canvas, cv::Rect(300, 200, 380, 300), cv::Scalar(90), cv::FILLED);
  const auto spec = vision::parse_charuco_spec("5x7", 20, 15, "DICT_4X4_50");
  const auto flat = vision::detect_charuco(canvas, spec);
  REQUIRE(flat.found);
  CHECK(flat.corners.size() < 24u);  // some inner corners are covered
  CHECK(flat.px_per_mm == Approx(10.0).epsilon(0.01));
  CHECK(flat.fit_rms_px < 1.0);

  // In perspective: a homography that shrinks the far side.
  const std::vector<cv::Point2f> src{{0, 0}, {1600, 0}, {1600, 1800}, {0, 1800}};
  const std::vector<cv::Point2f> dst{{150, 100}, {1450, 100}, {1600, 1800}, {0, 1800}};
  const cv::Mat P = cv::getPerspectiveTransform(src, dst);
  cv::Mat seen;
  cv::warpPerspective(canvas, seen, P, canvas.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(255));
  const auto tilted = vision::detect_charuco(seen, spec);
  REQUIRE(tilted.found);
  // The board-plane map undoes the perspective: every visible corner lands on the board's
  // 20 mm grid (origin at the first inner corner, covered or not).
  const cv::Matx33d H = tilted.img_to_mm;
  double x_min = 1e9, x_max = -1e9;
  for (const auto& c : tilted.corners) {
    const cv::Vec3d q = H * cv::Vec3d(c.x, c.y, 1);
    const double x = q[0] / q[2], y = q[1] / q[2];
    CHECK(x == Approx(20.0 * std::round(x / 20.0)).margin(0.3));
    CHECK(y == Approx(20.0 * std::round(y / 20.0)).margin(0.3));
    x_min = std::min(x_min, x);
    x_max = std::max(x_max, x);
  }
  CHECK(x_max - x_min == Approx(60.0).margin(0.5));  // 4 inner corners across a 5-square board
}
