// A G-code file as the commanded-speed input (issue 6, part 3): a rendered photo of a line
// printed by a G-code whose feed steps up half-way, the width following the step as a
// first-order lag; `tunekit linewidth --gcode --profile-csv` maps it to time with the
// set-point width the feed implied, and `tunekit step` identifies the lag.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "synthetic_render.hpp"
#include "test_support.hpp"
#include "tunekit/formats/csv.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/vision/width_to_dynamics.hpp"

using namespace tunekit;
namespace rd = tunekit::test::render;
using tunekit::test::run_cli;
namespace fs = std::filesystem;

TEST_CASE(
    "G-code as commanded speed: photo of a feed step -> tunekit linewidth --gcode -> tunekit step finds the lag") {
  const double d = 1.75, h = 0.2, area = M_PI * 0.25 * d * d;
  const double v = 20.0;                       // mm/s (F1200)
  const double w1 = 1.0, w2 = 1.4, tau = 0.4;  // mm, mm, s
  const double l1 = 30.0, l2 = 60.0;           // mm of path before / after the feed step
  const double e1 = w1 * l1 * h / area, e2 = w2 * l2 * h / area;
  const auto dir = test::scratch_dir("lw_gcode");
  const std::string gcode = dir + "/line.gcode";
  {
    std::ofstream g(gcode);
    g << "; one line, feed step half-way\nG21\nG90\nM83\nG1 Z0.2 F600\nG1 X10 Y20 F6000 ; travel\n"
      << fmt::format("G1 X{} Y20 E{:.5f} F{}\n", 10 + l1, e1, v * 60)
      << fmt::format("G1 X{} Y20 E{:.5f}\n", 10 + l1 + l2, e2) << "G1 E-0.8 F2400 ; retract\nG1 X0 Y0 F6000\n";
  }
  // The photo: 10 px/mm, X mm -> (X - 5) * 10 px, the line along y = 150 px; its width after the
  // step at t1 = l1 / v rises as w1 + (w2 - w1) (1 - exp(-(t - t1) / tau)).
  const double ppm = 10.0, t1 = l1 / v;
  auto width_at_x = [&](double x_px) {
    const double t = (x_px / ppm + 5.0 - 10.0) / v;
    return (t < t1 ? w1 : w1 + (w2 - w1) * (1.0 - std::exp(-(t - t1) / tau))) * ppm;
  };
  const double x0 = 50, x1 = 950, yc = 150.3;
  const rd::Sdf line = [&](double x, double y) {
    const double along = std::max(x0 - x, x - x1);
    return std::max(along, std::abs(y - yc) - 0.5 * width_at_x(std::clamp(x, x0, x1)));
  };
  rd::Photo ph;
  ph.blur_px = 1.0;
  ph.noise = 2.0;
  ph.vignetting = 0.3;
  const std::string img = dir + "/line.png";
  vision::write_png(img, rd::photograph(rd::coverage(1000, 300, line), ph));

  const std::string csv = dir + "/line.csv";
  const auto lw = run_cli({"linewidth", img, "--px-per-mm", "10", "--gcode", gcode, "--filament-diameter-mm", "1.75",
                           "--layer-height-mm", "0.2", "--profile-csv", csv, "--json"});
  INFO(lw.err);
  REQUIRE(lw.code == 0);
  const auto j = nlohmann::json::parse(lw.out);
  const auto& map = j["results"]["profile_csv"];
  CHECK(map["kind"] == "gcode");
  CHECK(map["segments"].get<int>() == 2);
  CHECK(map["path_length_mm"].get<double>() == Approx(l1 + l2));
  CHECK(map["path_duration_s"].get<double>() == Approx((l1 + l2) / v));
  CHECK(map["setpoint"] == "feed");

  // The CSV: set-point from the feed (w1 before the step, w2 after), time from the speed.
  formats::CsvOptions co;
  const auto table = formats::read_csv(csv, co);
  const auto& t = table.column("time").values;
  const auto& sp = table.column("setpoint_width").values;
  const auto& w = table.column("width").values;
  REQUIRE(t.size() > 700);
  int before = 0, after = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t1 - 0.01) {
      CHECK(sp[i] == Approx(w1).epsilon(1e-4));
      ++before;
    }
    if (t[i] > t1 + 0.01) {
      CHECK(sp[i] == Approx(w2).epsilon(1e-4));
      ++after;
    }
    // Where the line is settled, the measured width is the set-point.
    if (t[i] > t1 + 6 * tau) CHECK(w[i] == Approx(w2).margin(0.02));
  }
  CHECK(before > 200);
  CHECK(after > 500);

  // tunekit step on that CSV: a first-order lag of tau with unit gain.
  const auto st = run_cli({"step", csv, "--time", "time", "--input", "setpoint_width", "--output", "width", "--json"});
  INFO(st.err);
  INFO(st.out.substr(0, 3000));
  REQUIRE(st.code == 0);
  const auto js = nlohmann::json::parse(st.out);
  // Find tau_s and K values wherever the step report puts its fit.
  double tau_fit = NAN, k_fit = NAN;
  std::function<void(const nlohmann::json&)> walk = [&](const nlohmann::json& n) {
    if (n.is_object()) {
      if (n.contains("tau_s") && n["tau_s"].is_object() && n["tau_s"].contains("value") && std::isnan(tau_fit))
        tau_fit = n["tau_s"]["value"].get<double>();
      if (n.contains("K") && n["K"].is_object() && n["K"].contains("value") && std::isnan(k_fit))
        k_fit = n["K"]["value"].get<double>();
      for (const auto& [key, val] : n.items()) walk(val);
    } else if (n.is_array()) {
      for (const auto& val : n) walk(val);
    }
  };
  walk(js["results"]);
  INFO(fmt::format("tau {:.4f} s (rendered {}), K {:.4f} (rendered 1)", tau_fit, tau, k_fit));
  CHECK(tau_fit == Approx(tau).epsilon(0.05));
  CHECK(k_fit == Approx(1.0).epsilon(0.03));
}

TEST_CASE("map_path: a sample whose window holds the feed change carries the set-point's mean over its window") {
  // Two segments at 20 mm/s; the feed per mm rises by half at 10 mm. Samples every 0.1 mm, one of
  // them 0.02 mm before the change: its window (+-0.05 mm) holds 0.03 mm of the new level.
  const double d = 1.75, h = 0.2, area = M_PI * 0.25 * d * d;
  const double v = 20.0, w_lo = 0.4, w_hi = 0.6;
  const std::vector<vision::PathSegment> path{{10.0, v, w_lo * h * 10.0 / area}, {10.0, v, w_hi * h * 10.0 / area}};
  std::vector<double> s, w, c;
  for (int i = 0; i < 190; ++i) {
    s.push_back(0.58 + 0.1 * i);  // 9.98 mm at i = 94
    w.push_back(0.5);
    c.push_back(1.0);
  }
  vision::PathMapping how;
  how.offset_mm = 0.58;
  how.filament_diameter_mm = d;
  how.layer_height_mm = h;
  const auto rows = vision::map_path(s, w, c, path, how);
  REQUIRE(rows.size() == s.size());
  CHECK(rows[93].setpoint_mm == Approx(w_lo).epsilon(1e-9));
  CHECK(rows[94].setpoint_mm == Approx(0.7 * w_lo + 0.3 * w_hi).epsilon(1e-6));
  CHECK(rows[95].setpoint_mm == Approx(w_hi).epsilon(1e-9));
  CHECK(rows[94].t_s == Approx(9.98 / v).epsilon(1e-9));
}
