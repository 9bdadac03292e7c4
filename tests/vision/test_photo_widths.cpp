// measure_photo_widths, the one photo-to-widths pipeline: the scale it chooses (and why), and the
// ring test's gain and phase on a rendered ring whose width response is known.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "synthetic_render.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/vision/photo_widths.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;

namespace {

constexpr double kPxPerMm = 10;

// A 0.6 mm line, 60 mm long, on a 700 x 200 px photo at kPxPerMm.
cv::Mat line_photo(double width_mm) {
  const auto cov = rd::coverage(700, 200, rd::straight_line(50, 100, 650, 100, width_mm * kPxPerMm));
  rd::Photo ph;
  ph.noise = 1.0;
  ph.seed = 11;
  return rd::photograph(cov, ph);
}

}  // namespace

TEST_CASE("measure_photo_widths: a stated scale beats the nominal width, which is the last resort", "[photo_widths]") {
  const cv::Mat photo = line_photo(0.6);
  vision::PhotoWidthsRequest req;
  req.scale.px_per_mm = kPxPerMm;
  req.scale.nominal_width_mm = 0.5;
  const auto stated = vision::measure_photo_widths(photo, req, "line.png");
  REQUIRE(stated.failure.empty());
  CHECK(stated.scale.source == vision::ScaleSource::stated);
  CHECK(stated.scale.px_per_mm == kPxPerMm);
  REQUIRE(stated.scale.passed_over.size() == 1);
  CHECK(stated.scale.passed_over[0].find("nominal width") != std::string::npos);
  REQUIRE(stated.lines.size() == 1);
  CHECK(stated.lines[0].median_mm == Approx(0.6).margin(0.01));
  // The centreline stops short of the square ends (about a width or two each).
  CHECK(stated.lines[0].length_mm > 55);
  CHECK(stated.lines[0].length_mm < 60);

  req.scale.px_per_mm = 0;
  const auto nominal = vision::measure_photo_widths(photo, req, "line.png");
  REQUIRE(nominal.failure.empty());
  CHECK(nominal.scale.source == vision::ScaleSource::nominal_width);
  CHECK(nominal.scale.px_per_mm == Approx(kPxPerMm * 0.6 / 0.5).epsilon(0.02));
  CHECK(nominal.lines[0].mean_mm == Approx(0.5).epsilon(1e-9));

  req.scale = {};
  CHECK_THROWS_AS(vision::measure_photo_widths(photo, req, "line.png"), InputError);
}

TEST_CASE("measure_photo_widths: a flow-modulated ring gives the rendered gain and phase", "[photo_widths]") {
  // Set-point w0 (1 + A sin(N theta)) (the ring-print protocol), theta counterclockwise from
  // +x in the photo; the rendered width answers with gain g and lag `lag`.
  const double w0 = 1.0, A = 0.3, g = 0.6, lag = 40 * std::numbers::pi / 180, R = 25;
  const int N = 4;
  const double cx = 320.4, cy = 319.7;
  const auto cov = rd::coverage(640, 640, rd::ring(cx, cy, R * kPxPerMm, [&](double phi) {
                                  return (w0 + g * A * w0 * std::sin(N * phi - lag)) * kPxPerMm;
                                }));
  rd::Photo ph;
  ph.bed = 50;
  ph.line = 190;
  ph.noise = 1.5;
  ph.seed = 5;
  vision::PhotoWidthsRequest req;
  req.scale.px_per_mm = kPxPerMm;
  vision::RingTest ring;
  ring.sines = N;
  ring.speed_mm_s = 20;
  ring.radius_mm = R;
  ring.setpoint_width_mm = w0;
  ring.setpoint_amplitude_mm = A * w0;
  req.ring_test = ring;
  const auto pw = vision::measure_photo_widths(rd::photograph(cov, ph), req, "ring.png");
  REQUIRE(pw.failure.empty());
  REQUIRE(pw.ring);
  CHECK(pw.ring->freq_hz == Approx(N * ring.speed_mm_s / (2 * std::numbers::pi * R)).epsilon(1e-12));
  CHECK(pw.ring->gain == Approx(g).epsilon(0.03));
  CHECK(pw.ring->phase_deg == Approx(-40).margin(2));
  CHECK(pw.ring->centre_px.x == Approx(cx).margin(0.2));
  CHECK(pw.ring->measured_radius_mm == Approx(R).epsilon(0.005));
}
