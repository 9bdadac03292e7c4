// `tunekit linewidth` end to end on rendered photos: JSON shape, scale targets, errors and
// exit codes, overlays, and the profile CSV against time (issue 6).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>

#include "synthetic_render.hpp"
#include "test_support.hpp"
#include "tunekit/vision/camera_calibration.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/line_width.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;
using tunekit::test::run_cli;
namespace fs = std::filesystem;

namespace {

std::string save(const std::string& dir, const std::string& name, const cv::Mat& img) {
  const std::string p = (fs::path(dir) / name).string();
  vision::write_png(p, img);
  return p;
}

nlohmann::json parse(const test::CliRun& r) {
  INFO(r.err);
  REQUIRE(r.code == 0);
  return nlohmann::json::parse(r.out);
}

}  // namespace

TEST_CASE("linewidth --json lists lines with profile arrays and width_mm {mean, std} and writes the overlay") {
  const auto dir = test::scratch_dir("lw_json");
  const auto cov = rd::coverage(
      640, 480, rd::unite({rd::straight_line(60, 140, 580, 150, 11.0), rd::straight_line(60, 330, 580, 310, 23.0)}));
  rd::Photo ph;
  ph.noise = 2.0;
  ph.vignetting = 0.3;
  const auto img = save(dir, "two.png", rd::photograph(cov, ph));
  const auto r = run_cli({"linewidth", img, "--px-per-mm", "10", "--json", "--overlay", dir + "/ov"});
  const auto j = parse(r);
  const auto& lines = j["results"]["lines"];
  REQUIRE(lines.size() == 2);
  std::vector<double> truth_mm = {1.1, 2.3};
  std::vector<nlohmann::json> ls = {lines[0], lines[1]};
  std::sort(ls.begin(), ls.end(), [](const auto& x, const auto& y) {
    return x["width_mm"]["mean"].template get<double>() < y["width_mm"]["mean"].template get<double>();
  });
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& l = ls[k];
    const auto& p = l["profile"];
    REQUIRE(p["s_mm"].size() == p["width_mm"].size());
    REQUIRE(p["confidence"].size() == p["width_mm"].size());
    REQUIRE(p["flags"].size() == p["width_mm"].size());
    CHECK(p["s_mm"].size() > 400);
    CHECK(l["width_mm"]["mean"].get<double>() == Approx(truth_mm[k]).margin(0.01));
    CHECK(l["width_mm"]["std"].get<double>() < 0.025);
    CHECK(l["width_mm"]["unit"] == "mm");
    CHECK(l["closed"] == false);
  }
  CHECK(j["results"]["images"][0]["px_per_mm"].get<double>() == 10.0);
  CHECK(fs::exists(dir + "/ov/two_overlay.png"));
  const cv::Mat ov = vision::read_image(dir + "/ov/two_overlay.png");
  CHECK(ov.cols == 640);
  // Deterministic output.
  const auto r2 = run_cli({"linewidth", img, "--px-per-mm", "10", "--json", "--overlay", dir + "/ov"});
  CHECK(r2.out == r.out);
}

TEST_CASE("linewidth errors: unreadable, empty, no line, touching the frame, no scale target, no scale") {
  const auto dir = test::scratch_dir("lw_errors");
  SECTION("missing file: exit 2") {
    const auto r = run_cli({"linewidth", dir + "/nope.png", "--px-per-mm", "10"});
    CHECK(r.code == 2);
    CHECK(r.err.find("no such file") != std::string::npos);
  }
  SECTION("empty and undecodable files: exit 2") {
    const auto empty = test::write_scratch("lw_empty.png", "");
    auto r = run_cli({"linewidth", empty, "--px-per-mm", "10"});
    CHECK(r.code == 2);
    CHECK(r.err.find("empty") != std::string::npos);
    const auto junk = test::write_scratch("lw_junk.png", "this is not a PNG file at all");
    r = run_cli({"linewidth", junk, "--px-per-mm", "10"});
    CHECK(r.code == 2);
    CHECK(r.err.find("cannot decode") != std::string::npos);
  }
  SECTION("a bare bed: exit 1 (measured nothing), overlay still written") {
    rd::Photo ph;
    ph.noise = 2;
    const auto img = save(dir, "bare.png", rd::photograph(cv::Mat::zeros(240, 320, CV_32F), ph));
    const auto r = run_cli({"linewidth", img, "--px-per-mm", "10", "--overlay", dir + "/ov"});
    CHECK(r.code == 1);
    CHECK(r.err.find("no line found") != std::string::npos);
    CHECK(fs::exists(dir + "/ov/bare_overlay.png"));
  }
  SECTION("a line touching the frame edge: exit 2 with the reason, overlay written; --allow-edge measures it") {
    const auto img =
        save(dir, "edge.png", rd::photograph(rd::coverage(320, 240, rd::straight_line(-40, 120, 250, 125, 10)), {}));
    auto r = run_cli({"linewidth", img, "--px-per-mm", "10", "--overlay", dir + "/ov"});
    CHECK(r.code == 2);
    CHECK(r.err.find("touches the frame edge") != std::string::npos);
    CHECK(fs::exists(dir + "/ov/edge_overlay.png"));
    r = run_cli({"linewidth", img, "--px-per-mm", "10", "--allow-edge", "--json"});
    const auto j = parse(r);
    CHECK(j["results"]["lines"][0]["touches_frame"] == true);
    CHECK(j["results"]["lines"][0]["width_mm"]["mean"].get<double>() == Approx(1.0).margin(0.01));
  }
  SECTION("scale target not found: exit 2, overlay written") {
    const auto img =
        save(dir, "noboard.png", rd::photograph(rd::coverage(320, 240, rd::straight_line(40, 120, 280, 125, 10)), {}));
    const auto r = run_cli({"linewidth", img, "--chessboard", "9x6", "--square-mm", "5", "--overlay", dir + "/ov"});
    CHECK(r.code == 2);
    CHECK(r.err.find("scale target not found") != std::string::npos);
    CHECK(fs::exists(dir + "/ov/noboard_overlay.png"));
  }
  SECTION("no scale given: exit 2") {
    const auto img =
        save(dir, "noscale.png", rd::photograph(rd::coverage(320, 240, rd::straight_line(40, 120, 280, 125, 10)), {}));
    const auto r = run_cli({"linewidth", img});
    CHECK(r.code == 2);
    CHECK(r.err.find("no scale") != std::string::npos);
  }
}

TEST_CASE("chessboard in the scene: scale within 0.2 % of the truth") {
  // 10 x 7 squares of 24 px = 4 mm: 6 px/mm; inner corners 9 x 6.
  const double sq_px = 24.0, sq_mm = 4.0, truth_ppm = sq_px / sq_mm;
  const auto cov =
      rd::coverage(800, 600,
                   rd::unite({rd::chessboard(60.3, 40.6, 10, 7, sq_px), rd::straight_line(80, 420, 720, 440, 12.0),
                              rd::straight_line(80, 520, 720, 505, 18.0)}));
  rd::Photo ph;
  ph.noise = 2.0;
  ph.vignetting = 0.3;
  ph.blur_px = 1.0;
  const cv::Mat photo = rd::photograph(cov, ph);
  const auto det = vision::detect_chessboard(vision::to_gray_float(photo), vision::parse_chessboard_spec("9x6", sq_mm));
  REQUIRE(det.found);
  INFO(fmt::format("px/mm {:.5f} (truth {:.5f}), corner fit RMS {:.4f} px", det.px_per_mm, truth_ppm, det.fit_rms_px));
  CHECK(std::abs(det.px_per_mm / truth_ppm - 1) <= 0.002);
}

TEST_CASE("Holtrup 2019 eq. 4.3: set-point amplitude and ring frequency") {
  vision::RingSine r;
  r.n_sines = 1;
  r.amplitude_mm = 0.1;
  r.speed_mm_s = 2;
  r.radius_mm = 30;
  r.rod_radius_mm = 2.5;
  r.layer_height_mm = 0.2;
  r.width_gcode_mm = 0.66;
  CHECK(vision::ring_setpoint_amplitude_mm(r) == Approx(M_PI * 0.1 * 6.25 / 6.0));
  CHECK(vision::ring_frequency_hz(r) == Approx(2.0 / (2 * M_PI * 30)));
  CHECK(vision::ring_setpoint_width_mm(r, 0) == Approx(0.66 - M_PI * 0.1 * 6.25 / 6.0));
  const double quarter = M_PI / 2 * 30 / 2;  // N v t / R = pi/2
  CHECK(vision::ring_setpoint_width_mm(r, quarter) == Approx(0.66));
}
