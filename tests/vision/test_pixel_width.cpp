// The width of a steady line as a camera's pixels record it: the edge measurement must not
// depend on where the edges fall between pixel centres. A width read 0.75 % narrow at one width
// and right at another turns into a width gain 1.6 % high between the line test's two widths.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/vision/line_width.hpp"

using namespace tunekit;

namespace {

double median(std::vector<double> v) {
  REQUIRE(!v.empty());
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

struct Measured {
  double width = 0, blur = 0;
};

// Median width and edge blur (px) of the longest line's valid samples.
Measured measure(const cv::Mat& img) {
  const auto r = vision::measure_line_widths(vision::to_gray_float(img));
  REQUIRE(!r.lines.empty());
  std::vector<double> w, b;
  for (const auto& s : r.lines.front().samples)
    if (s.valid()) {
      w.push_back(s.width_px);
      b.push_back(s.blur_px);
    }
  REQUIRE(w.size() > 100);
  return {median(w), median(b)};
}

// A horizontal bar of width w px centred at y = yc (pixel centres at integers), blurred by a
// Gaussian of sigma s, each pixel the light averaged over its area (closed form): bed 60, bar 200.
cv::Mat pixel_bar(double w, double yc, double s) {
  auto psi = [s](double x) {
    const double z = x / s;
    return s * (z * 0.5 * std::erfc(-z / std::sqrt(2.0)) + std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI));
  };
  auto edge = [&](double x) { return psi(x + 0.5) - psi(x - 0.5); };  // pixel centre x px inside an edge
  cv::Mat img(80, 300, CV_32F, cv::Scalar(60));
  for (int y = 0; y < img.rows; ++y) {
    const double d = std::abs(y - yc), cover = edge(w / 2 - d) + edge(w / 2 + d) - 1;
    for (int x = 40; x < 260; ++x) img.at<float>(y, x) = static_cast<float>(60 + 140 * cover);
  }
  return img;
}

}  // namespace

TEST_CASE("a bar recorded by pixels is measured to 0.005 px wherever its edges fall between pixel centres") {
  // Noise-free, so what is left is the estimator's own bias. Before the bar model averaged the
  // blurred edge over each pixel and the fit read the pixels rather than values interpolated
  // between them, it was up to 0.017 px (blur 0.6 px) and 0.023 px (blur 0.3 px) here.
  for (double s : {0.3, 0.6, 1.2})
    for (double w : {3.6, 4.86, 7.02, 8.4})
      for (double phase : {0.0, 0.125, 0.25, 0.375, 0.5}) {
        const Measured m = measure(pixel_bar(w, 40 + phase, s));
        INFO(fmt::format("blur {} px, width {} px, centre 40 + {} px: measured {:.5f} px, blur {:.4f} px", s, w, phase,
                         m.width, m.blur));
        CHECK(std::abs(m.width - w) < 0.005);
        CHECK(std::abs(m.blur - s) < 0.02 * s + 0.005);
      }
}

TEST_CASE("a steady line on the simulated camera's photo measures its commanded width within 0.2 %") {
  // The line test's widths (0.405 and 0.585 mm at 12 px/mm) and three around them put the edges
  // at different places between pixel centres. The simulated photo's bed texture and sensor
  // noise move the median of about 1800 samples by about 0.05 %; 0.2 % is four times that and a
  // quarter of the 0.75 % the 0.405 mm line was read narrow by when the photo was blurred after
  // its pixels were sampled and the edges were fitted to interpolated values.
  for (double w_mm : {0.3, 0.405, 0.5, 0.585, 0.7}) {
    auto bed = std::make_shared<sim::SimPrintBed>(3);
    const double h = 0.2, v = 20;
    bed->deposit(0, {35, 60, h, 0}, 0, 0);
    for (int i = 0; i <= 7500; ++i) bed->deposit(0, {35 + 0.02 * i, 60, h, 0}, v, w_mm * v * h);
    bed->deposit(0, {185, 60, h, 0}, 0, 0);
    const sim::SimCameraOptions o;
    const Measured m = measure(bed->photograph(o));
    INFO(fmt::format("commanded {} mm, measured {:.5f} mm, edge blur {:.3f} px", w_mm, m.width / o.px_per_mm, m.blur));
    CHECK(std::abs(m.width / o.px_per_mm / w_mm - 1) < 0.002);
    // The fitted edge blur is the simulated lens's (0.6 px), within 10 %.
    CHECK(std::abs(m.blur - o.blur_px) < 0.1 * o.blur_px);
  }
}

TEST_CASE("a ring on the simulated camera's photo is as bright on the outside of its curve as on the inside") {
  // A ring of 3 mm radius, 0.9 mm wide: its pieces (0.05 mm) turn by 1 deg each. Pieces bounded
  // square to their own direction left a wedge uncovered on the outside of each turn and covered
  // one twice on the inside, so the outer half was drawn dimmer by d / R (8 % 3 px out on this
  // ring; on the ring test's 30 mm that read its width modulation 0.05 % high).
  auto bed = std::make_shared<sim::SimPrintBed>(5);
  const double R = 3, w = 0.9, h = 0.2, v = 20, cx = 50, cy = 50;
  bed->deposit(0, {cx + R, cy, h, 0}, 0, 0);
  for (int i = 0; i <= 3000; ++i) {
    const double a = 2 * M_PI * i / 3000;
    bed->deposit(0, {cx + R * std::cos(a), cy + R * std::sin(a), h, 0}, v, w * v * h);
  }
  sim::SimCameraOptions o;
  o.vignetting = o.gradient = o.noise_sigma = 0;
  sim::SimCameraFrame frame;
  const cv::Mat img = bed->photograph(o, &frame);
  // Mean grey over the bead's interior, 0.1-0.3 of its width inside (-1) or outside (+1) the
  // centreline: 2 px or more from the edges, where the lens blur (0.6 px) has no reach.
  auto band = [&](int side) {
    double sum = 0;
    int n = 0;
    for (int v_px = 0; v_px < img.rows; ++v_px)
      for (int u_px = 0; u_px < img.cols; ++u_px) {
        const double x = frame.x0_mm + (u_px + 0.5) / frame.px_per_mm, y = frame.y1_mm - (v_px + 0.5) / frame.px_per_mm;
        const double d = side * (std::hypot(x - cx, y - cy) - R) / w;
        if (d > 0.1 && d < 0.3) sum += img.at<unsigned char>(v_px, u_px), ++n;
      }
    REQUIRE(n > 100);
    return sum / n;
  };
  const double inner = band(-1), outer = band(+1);
  INFO(fmt::format("inner half {:.2f}, outer half {:.2f} (filament {})", inner, outer, o.filament_level));
  CHECK(std::abs(outer - inner) < 0.5);
  CHECK(std::abs(outer - o.filament_level) < 0.5);
}
