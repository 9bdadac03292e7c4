// A line printed from rest: its width rises from no bead at all, below what the edge fit can
// measure. The line test's record of such a line must read the bed before the bead as width 0 and
// the thin start as its width, or the melt stored at the first level (the area between the feed
// and the rise) is wrong.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <vector>

#include <fmt/format.h>

#include "tunekit/sim/sim_camera.hpp"
#include "tunekit/vision/photo_widths.hpp"

using namespace tunekit;

TEST_CASE("a line's start from rest is measured from the bare bed through its thin rise to its width") {
  // A 10 mm run-up without extrusion from x = 25 mm, then a bead whose width rises as
  // w0 (1 - exp(-d / 2 mm)) over the distance d from x = 35 mm, on 100 mm at 20 mm/s.
  const double h = 0.2, v = 20, w0 = 0.405, lambda = 2.0, x_runup = 25, x_bead = 35, length = 100;
  auto width_at = [&](double x) { return x < x_bead ? 0.0 : w0 * (1 - std::exp(-(x - x_bead) / lambda)); };
  auto bed = std::make_shared<sim::SimPrintBed>(7);
  bed->deposit(0, {x_bead, 60, h, 0}, 0, 0);
  for (double x = x_bead; x <= x_bead + length + 1e-9; x += 0.01)
    bed->deposit(0, {x, 60, h, 0}, v, width_at(x) * v * h);
  bed->deposit(0, {x_bead + length, 60, h, 0}, 0, 0);
  const sim::SimCameraOptions o;
  sim::SimCameraFrame frame;
  const cv::Mat photo = bed->photograph(o, &frame);

  vision::PhotoWidthsRequest req;
  req.scale.px_per_mm = frame.px_per_mm;
  req.placement = {true, frame.x0_mm, frame.y1_mm};
  vision::LineTest test;
  test.filament_diameter_mm = 1.75;
  test.layer_height_mm = h;
  const double area = M_PI / 4 * 1.75 * 1.75;
  test.lines.push_back({x_runup, {{x_bead - x_runup, v, 0.0}, {length, v, w0 * h * length / area}}});
  req.line_test = test;
  const auto pw = vision::measure_photo_widths(photo, req, "simulated");
  INFO(pw.failure);
  REQUIRE(pw.failure.empty());
  REQUIRE(pw.line_test.size() == 1);
  for (const auto& w : pw.warnings) INFO(w);
  const auto& rows = pw.line_test.front().rows;
  // The record starts half-way along the run-up (its first half: the nozzle's start and a real
  // printer's ooze).
  REQUIRE(!rows.empty());
  CHECK(rows.front().s_mm == Approx(0.5 * (x_bead - x_runup)).margin(0.2));
  // Over the run-up the widths are the bare bed's: 0 within the noise; over the rise and after it
  // the commanded width at each position. The area the rise leaves under w0 (here w0 lambda, 0.81
  // mm^2) is what the melt stored at the first level is measured by: within 1 %.
  double bare = 0, missing = 0, missing_true = 0;
  std::size_t n_bare = 0;
  for (std::size_t i = 0; i + 1 < rows.size(); ++i) {
    const double x = x_runup + rows[i].s_mm, ds = rows[i + 1].s_mm - rows[i].s_mm;
    if (x < x_bead - 0.2) {
      bare += rows[i].width_mm, ++n_bare;
    } else if (x > x_bead && x < x_bead + 10 * lambda) {
      missing += (w0 - rows[i].width_mm) * ds;
      missing_true += (w0 - width_at(x)) * ds;
    }
  }
  REQUIRE(n_bare > 40);
  INFO(fmt::format("bare bed {:.5f} mm over {} samples; area under w0 {:.5f} mm^2, true {:.5f}", bare / n_bare, n_bare,
                   missing, missing_true));
  CHECK(std::abs(bare / static_cast<double>(n_bare)) < 0.005);
  CHECK(missing == Approx(missing_true).epsilon(0.01));
}
