// The overshoot grid's report figure: overshoot and the figure of merit against acceleration,
// one line per speed (Hemminger, Improvements and Characterization of Error, Speed, and
// Capabilities in Low-Cost Additive Manufacturing Systems, MS thesis, UCLA, 2022, plots the
// overshoot error over the acceleration-velocity grid the same way).
#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "tunekit/calibration/presentation/report.hpp"

namespace tunekit::calibration {

Figure overshoot_grid_figure(const OvershootGridPlot& d) {
  Figure f;
  f.title = "Overshoot grid: speed x acceleration";
  std::map<std::pair<bool, double>, std::vector<std::pair<double, const OvershootGridPlot::Cell*>>> by_speed;
  for (const auto& c : d.cells) by_speed[{c.input_shaping, c.speed_mm_s}].push_back({c.accel_mm_s2, &c});
  Panel os{"Overshoot (mean over corners, worst axis)", "", "overshoot (mm)", false, false, {}, 1.2};
  Panel fom{"Figure of merit (normalized speed within tolerance, else 0)",
            "acceleration (mm/s^2)",
            "FOM",
            false,
            false,
            {},
            1.0};
  Panel ct{"Completion time of the motion", "", "time (s)", false, false, {}, 0.8};
  int color = 1;
  std::vector<double> ax_all;
  for (auto& [key, cells] : by_speed) {
    const auto [shaped, v] = key;
    std::sort(cells.begin(), cells.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto style = shaped ? Series::Style::dashed : Series::Style::line;
    const std::string label = fmt::format("{:g} mm/s{}", v, shaped ? " shaped" : "");
    Series so{label, {}, {}, style, color};
    Series sf{label, {}, {}, style, color};
    Series sc{"", {}, {}, style, color};
    for (const auto& [acc, c] : cells) {
      so.x.push_back(acc);
      so.y.push_back(c->overshoot_mm);
      sf.x.push_back(acc);
      sf.y.push_back(c->figure_of_merit);
      sc.x.push_back(acc);
      sc.y.push_back(c->completion_time_s);
      ax_all.push_back(acc);
    }
    os.series.push_back(so);
    fom.series.push_back(sf);
    ct.series.push_back(sc);
    color = color % 8 + 1;
  }
  if (!ax_all.empty()) {
    const double tol = d.tolerance_mm;
    const auto [lo, hi] = std::minmax_element(ax_all.begin(), ax_all.end());
    os.series.push_back({"tolerance", {*lo, *hi}, {tol, tol}, Series::Style::dashed, 8});
  }
  f.panels = {os, ct, fom};
  f.height_px = 820;
  return f;
}

}  // namespace tunekit::calibration
