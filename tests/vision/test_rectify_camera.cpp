// Scale through perspective (issue 6, part 1): photos of the bed plane taken by a tilted
// pinhole camera (rendered exactly through the plane's homography), measured with
// `tunekit linewidth --chessboard ... --rectify`, and a camera profile from several chessboard
// views (`--save-camera`) used later with `--camera PROFILE --rectify`.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>

#include "synthetic_render.hpp"
#include "test_support.hpp"
#include "tunekit/vision/image_io.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;
using tunekit::test::run_cli;
namespace fs = std::filesystem;

namespace {

constexpr int kW = 800, kH = 600;
constexpr double kFocalPx = 800;

// Bed plane (mm, z = 0) -> image px for a camera at distance `tz_mm` looking at the plane with
// the rotation vector (rx, ry, rz) (rad) and the plane origin shifted by (tx, ty) mm.
cv::Matx33d plane_to_image(double rx, double ry, double rz, double tx, double ty, double tz_mm) {
  cv::Matx33d R;
  cv::Rodrigues(cv::Vec3d(rx, ry, rz), R);
  const cv::Matx33d K(kFocalPx, 0, 0.5 * (kW - 1), 0, kFocalPx, 0.5 * (kH - 1), 0, 0, 1);
  const cv::Matx33d M(R(0, 0), R(0, 1), tx, R(1, 0), R(1, 1), ty, R(2, 0), R(2, 1), tz_mm);
  return K * M;
}

// Smallest mm-per-image-px over the image (keeps the renderer's edge band wide enough).
double min_mm_per_px(const cv::Matx33d& img_to_plane) {
  double best = 1e300;
  for (int y = 0; y <= kH; y += kH / 6)
    for (int x = 0; x <= kW; x += kW / 8) {
      auto at = [&](double u, double v) {
        const cv::Vec3d q = img_to_plane * cv::Vec3d(u, v, 1.0);
        return cv::Point2d(q[0] / q[2], q[1] / q[2]);
      };
      const cv::Point2d a = at(x, y), b = at(x + 1, y), c = at(x, y + 1);
      best = std::min({best, std::hypot(b.x - a.x, b.y - a.y), std::hypot(c.x - a.x, c.y - a.y)});
    }
  return best;
}

cv::Mat photo_of_plane(const rd::Sdf& plane_mm, const cv::Matx33d& plane_to_img, unsigned seed) {
  const cv::Matx33d inv = plane_to_img.inv();
  const auto cov = rd::coverage(kW, kH, rd::warped(plane_mm, inv, min_mm_per_px(inv)), 8, 2.5);
  rd::Photo ph;
  ph.blur_px = 1.0;
  ph.noise = 1.5;
  ph.vignetting = 0.25;
  ph.seed = seed;
  return rd::photograph(cov, ph);
}

// The chessboard: 10 x 7 squares of `sq` mm, first inner corner at the origin.
rd::Sdf board(double sq) { return rd::chessboard(-sq, -sq, 10, 7, sq); }

nlohmann::json run_json(const std::vector<std::string>& args) {
  const auto r = run_cli(args);
  INFO(r.err);
  REQUIRE(r.code == 0);
  return nlohmann::json::parse(r.out);
}

// Width statistics (mm) of the JSON lines, narrowest first.
std::vector<std::pair<double, double>> widths(const nlohmann::json& j) {
  std::vector<std::pair<double, double>> out;
  for (const auto& l : j["results"]["lines"])
    out.emplace_back(l["width_mm"]["mean"].get<double>(), l["width_mm"]["std"].get<double>());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE(
    "tilted camera: --chessboard --rectify measures widths in mm across the bed (without it the perspective shows)") {
  const double sq = 5.0;  // mm
  // Two lines on the bed below the board, 1.2 mm and 2.0 mm wide, 70 mm long.
  const auto scene =
      rd::unite({board(sq), rd::straight_line(-10, 42, 60, 42, 1.2), rd::straight_line(-10, 54, 60, 54, 2.0)});
  // Camera tilted by 0.45 rad about x (strong keystone), board near the top of the frame.
  const cv::Matx33d H = plane_to_image(0.45, 0.05, 0.02, -25, -28, 150);
  const auto dir = test::scratch_dir("lw_rectify");
  const std::string img = dir + "/tilted.png";
  vision::write_png(img, photo_of_plane(scene, H, 5));

  const auto rect = run_json({"linewidth", img, "--chessboard", "9x6", "--square-mm", fmt::format("{}", sq),
                              "--rectify", "--json", "--overlay", dir + "/ov"});
  const auto wr = widths(rect);
  REQUIRE(wr.size() == 2);
  INFO(fmt::format("rectified: {:.4f} mm (std {:.4f}), {:.4f} mm (std {:.4f})", wr[0].first, wr[0].second, wr[1].first,
                   wr[1].second));
  CHECK(wr[0].first == Approx(1.2).margin(0.02));
  CHECK(wr[1].first == Approx(2.0).margin(0.02));
  CHECK(wr[0].second < 0.02);
  CHECK(wr[1].second < 0.02);
  CHECK(rect["results"]["images"][0]["scale_source"].get<std::string>().find("rectified") != std::string::npos);
  CHECK(fs::exists(dir + "/ov/tilted_overlay.png"));

  // The same photo with only the scale at the board's centre: the lines lie elsewhere on the
  // tilted bed, where the image scale differs, so their widths come out wrong by more than 5 %;
  // that is what --rectify removes.
  const auto plain =
      run_json({"linewidth", img, "--chessboard", "9x6", "--square-mm", fmt::format("{}", sq), "--json"});
  const auto wp = widths(plain);
  REQUIRE(wp.size() == 2);
  INFO(fmt::format("not rectified: {:.4f} and {:.4f} mm", wp[0].first, wp[1].first));
  CHECK(std::abs(wp[0].first / 1.2 - 1) > 0.05);
  CHECK(std::abs(wp[1].first / 2.0 - 1) > 0.05);
}

TEST_CASE("camera profile: --save-camera from chessboard views then --camera PROFILE --rectify measures a photo") {
  const double sq = 5.0;
  const auto dir = test::scratch_dir("lw_camera");
  // The first view is the measuring pose (board lying on the bed); the others vary the pose.
  const cv::Matx33d bed_pose = plane_to_image(0.35, -0.05, 0.03, -22, -10, 160);
  const cv::Matx33d poses[] = {
      bed_pose, plane_to_image(-0.3, 0.25, -0.1, -20, -15, 150), plane_to_image(0.1, -0.4, 0.2, -25, -12, 140),
      plane_to_image(-0.25, -0.3, 0.6, -15, -20, 170), plane_to_image(0.4, 0.3, -0.4, -25, -5, 155)};
  std::vector<std::string> cal = {"linewidth"};
  unsigned seed = 20;
  for (std::size_t i = 0; i < std::size(poses); ++i) {
    const std::string p = fmt::format("{}/cal_{}.png", dir, i);
    vision::write_png(p, photo_of_plane(board(sq), poses[i], seed++));
    cal.push_back(p);
  }
  const std::string profile = dir + "/cam.json";
  for (const char* a : {"--chessboard", "9x6", "--square-mm", "5", "--save-camera"}) cal.emplace_back(a);
  cal.push_back(profile);
  cal.emplace_back("--json");
  const auto jc = run_json(cal);
  const auto& cam = jc["results"]["camera"];
  INFO(cam.dump());
  CHECK(cam["images_used"].get<int>() == 5);
  CHECK(cam["rms_reprojection_px"].get<double>() < 0.3);
  CHECK(cam["camera_matrix"][0][0].get<double>() == Approx(kFocalPx).epsilon(0.02));
  REQUIRE(fs::exists(profile));

  // A later photo from the measuring pose: two lines on the bed, no target in the scene.
  const auto scene = rd::unite({rd::straight_line(-5, 8, 50, 9, 1.0), rd::straight_line(-5, 24, 50, 22, 1.8)});
  const std::string shot = dir + "/shot.png";
  vision::write_png(shot, photo_of_plane(scene, bed_pose, 40));
  const auto jm = run_json({"linewidth", shot, "--camera", profile, "--rectify", "--json"});
  const auto w = widths(jm);
  REQUIRE(w.size() == 2);
  INFO(fmt::format("camera profile, rectified: {:.4f} mm (std {:.4f}), {:.4f} mm (std {:.4f})", w[0].first, w[0].second,
                   w[1].first, w[1].second));
  CHECK(w[0].first == Approx(1.0).margin(0.02));
  CHECK(w[1].first == Approx(1.8).margin(0.02));
  CHECK(jm["results"]["images"][0]["scale_source"] == "camera profile bed plane, rectified");

  // A photo of another size than the calibrated one is refused.
  const std::string small = dir + "/small.png";
  vision::write_png(small, cv::Mat(300, 400, CV_8U, cv::Scalar(128)));
  const auto r = run_cli({"linewidth", small, "--camera", profile});
  CHECK(r.code == 2);
  CHECK(r.err.find("calibrated at 800x600") != std::string::npos);
}
