// Line-width measurement on rendered photos with known truth (issue 6, "Done when" line 1).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "synthetic_render.hpp"
#include "tunekit/vision/line_width.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;

namespace {

struct Stats {
  double mean = 0, std = 0;
  int n = 0;
};

Stats width_stats(const vision::MeasuredLine& l) {
  Stats s;
  s.mean = l.mean_width_px;
  s.std = l.std_width_px;
  s.n = l.valid_samples;
  return s;
}

}  // namespace

TEST_CASE("straight lines 6-40 px: bias <= 0.1 px and std <= 0.25 px with blur, noise and vignetting") {
  struct Case {
    double w, angle_deg;
    bool dark;
  };
  const Case cases[] = {{6, 0, true},   {6, 33, false},   {8.5, 71, true}, {10, 12, true}, {14.3, 90, false},
                        {20, 45, true}, {25.7, 5, false}, {32, 58, true},  {40, 21, true}, {40, 84, false}};
  unsigned seed = 11;
  for (const auto& c : cases) {
    const int W = 640, H = 480;
    const double a = c.angle_deg * M_PI / 180.0, half = 230;
    const double cx = 0.5 * W + 3.3, cy = 0.5 * H - 2.7;
    const double sa = std::abs(std::sin(a));
    const double L = sa > 1e-9 ? std::min(half, (0.5 * H - c.w - 10) / sa) : half;
    const auto cov = rd::coverage(
        W, H,
        rd::straight_line(cx - std::cos(a) * L, cy - std::sin(a) * L, cx + std::cos(a) * L, cy + std::sin(a) * L, c.w));
    rd::Photo ph;
    ph.bed = c.dark ? 210 : 45;
    ph.line = c.dark ? 70 : 190;
    ph.blur_px = 1.2;
    ph.vignetting = 0.35;
    ph.noise = 2.0;
    ph.seed = seed++;
    const cv::Mat img = rd::photograph(cov, ph);
    const auto res = vision::measure_line_widths(vision::to_gray_float(img));
    INFO(fmt::format("width {} px at {} deg, {} line", c.w, c.angle_deg, c.dark ? "dark" : "light"));
    REQUIRE(res.lines.size() == 1);
    CHECK(res.light_lines == !c.dark);
    const auto s = width_stats(res.lines[0]);
    INFO(fmt::format("mean {:.4f} std {:.4f} n {}", s.mean, s.std, s.n));
    CHECK(s.n > 0.9 * res.lines[0].samples.size());
    CHECK(s.n > 100);
    CHECK(std::abs(s.mean - c.w) <= 0.1);
    CHECK(s.std <= 0.25);
    CHECK_FALSE(res.lines[0].closed);
    CHECK_FALSE(res.lines[0].touches_frame);
  }
}

TEST_CASE("a curved line (polyline with round joins) is followed and measured without bias") {
  std::vector<cv::Point2d> pts;
  for (int i = 0; i <= 200; ++i) {
    const double x = 60 + 2.6 * i;
    pts.push_back({x, 240 + 110 * std::sin(x / 90.0)});
  }
  const double w = 12.0;
  const auto cov = rd::coverage(640, 480, rd::polyline(pts, w));
  rd::Photo ph;
  ph.blur_px = 1.0;
  ph.noise = 2.0;
  ph.vignetting = 0.2;
  const auto res = vision::measure_line_widths(vision::to_gray_float(rd::photograph(cov, ph)));
  REQUIRE(res.lines.size() == 1);
  const auto s = width_stats(res.lines[0]);
  INFO(fmt::format("mean {:.4f} std {:.4f} n {} length {:.1f}", s.mean, s.std, s.n, res.lines[0].length_px));
  CHECK(std::abs(s.mean - w) <= 0.1);
  CHECK(s.std <= 0.25);
  CHECK(res.lines[0].length_px > 500);
}

TEST_CASE("the stations measured on worker threads give the samples of one thread, bit for bit") {
  std::vector<cv::Point2d> pts;
  for (int i = 0; i <= 200; ++i) {
    const double x = 60 + 2.6 * i;
    pts.push_back({x, 240 + 110 * std::sin(x / 90.0)});
  }
  const auto cov = rd::coverage(640, 480, rd::polyline(pts, 12.0));
  rd::Photo ph;
  ph.noise = 2.0;
  const cv::Mat gray = vision::to_gray_float(rd::photograph(cov, ph));
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  const auto one = vision::measure_line_widths(gray);
  cv::setNumThreads(4);
  const auto several = vision::measure_line_widths(gray);
  cv::setNumThreads(threads);
  REQUIRE(one.lines.size() == 1);
  REQUIRE(several.lines.size() == 1);
  const auto& a = one.lines[0].samples;
  const auto& b = several.lines[0].samples;
  REQUIRE(a.size() == b.size());
  REQUIRE(a.size() > 400);
  int differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i].width_px, &b[i].width_px, sizeof(double)) != 0 || a[i].x_px != b[i].x_px ||
        a[i].flags != b[i].flags)
      ++differing;
  CHECK(differing == 0);
}

TEST_CASE("a ring with a sine-modulated width yields the amplitude within 3 % and the phase within 3 deg") {
  const double cx = 400.4, cy = 398.7, R = 300, w0 = 14, amp = 2.0, N = 3, phase = 0.7;
  const auto cov =
      rd::coverage(800, 800, rd::ring(cx, cy, R, [&](double phi) { return w0 + amp * std::cos(N * phi - phase); }));
  rd::Photo ph;
  ph.blur_px = 1.0;
  ph.noise = 2.0;
  ph.vignetting = 0.3;
  const auto res = vision::measure_line_widths(vision::to_gray_float(rd::photograph(cov, ph)));
  REQUIRE(res.lines.size() == 1);
  const auto& l = res.lines[0];
  CHECK(l.closed);
  // Linear least squares of width = m + p cos(N phi) + q sin(N phi).
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& s : l.samples) {
    if (!s.valid()) continue;
    const double phi = std::atan2(-(s.y_px - cy), s.x_px - cx);
    const Eigen::Vector3d r(1.0, std::cos(N * phi), std::sin(N * phi));
    A += r * r.transpose();
    b += r * s.width_px;
    ++n;
  }
  const Eigen::Vector3d x = A.ldlt().solve(b);
  const double amp_m = std::hypot(x(1), x(2)), phase_m = std::atan2(x(2), x(1));
  INFO(fmt::format("n {} mean {:.4f} amp {:.4f} phase {:.4f} rad", n, x(0), amp_m, phase_m));
  CHECK(n > 0.95 * l.samples.size());
  CHECK(std::abs(amp_m / amp - 1) <= 0.03);
  CHECK(std::abs(phase_m - phase) * 180 / M_PI <= 3.0);
  CHECK(std::abs(x(0) - w0) <= 0.1);
}

TEST_CASE("a line running off the image is reported as touching the frame") {
  const auto cov = rd::coverage(320, 240, rd::straight_line(-50, 120, 200, 130, 10));
  const auto res = vision::measure_line_widths(vision::to_gray_float(rd::photograph(cov, rd::Photo{})));
  REQUIRE(res.lines.size() == 1);
  CHECK(res.lines[0].touches_frame);
}

TEST_CASE("an image of a bare bed has no lines") {
  rd::Photo ph;
  ph.noise = 3.0;
  ph.vignetting = 0.4;
  const cv::Mat cov = cv::Mat::zeros(240, 320, CV_32F);
  const auto res = vision::measure_line_widths(vision::to_gray_float(rd::photograph(cov, ph)));
  CHECK(res.lines.empty());
}

TEST_CASE("two lines close together are flagged as merged where a neighbour enters the window") {
  // Parallel lines 12 px wide, 4 px apart over the right half only.
  std::vector<rd::Sdf> parts{rd::straight_line(40, 200, 600, 200, 12),
                             rd::polyline({{40, 260}, {300, 260}, {340, 216}, {600, 216}}, 12)};
  const auto cov = rd::coverage(640, 400, rd::unite(parts));
  const auto res = vision::measure_line_widths(vision::to_gray_float(rd::photograph(cov, rd::Photo{})));
  REQUIRE_FALSE(res.lines.empty());
  int merged = 0;
  for (const auto& l : res.lines)
    for (const auto& s : l.samples)
      if (s.flags & vision::kFlagMerged) ++merged;
  CHECK(merged > 20);
}
