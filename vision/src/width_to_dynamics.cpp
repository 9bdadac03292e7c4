#include "tunekit/vision/width_to_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "ring_geometry.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::vision {

double ring_frequency_hz(const RingSine& r) { return r.n_sines * r.speed_mm_s / (2.0 * M_PI * r.radius_mm); }

double ring_setpoint_amplitude_mm(const RingSine& r) {
  return M_PI * r.amplitude_mm * r.n_sines * r.rod_radius_mm * r.rod_radius_mm / (r.layer_height_mm * r.radius_mm);
}

double ring_setpoint_width_mm(const RingSine& r, double t_s) {
  return r.width_gcode_mm - ring_setpoint_amplitude_mm(r) * std::cos(r.n_sines * t_s * r.speed_mm_s / r.radius_mm);
}

cv::Vec3d fit_circle(const std::vector<cv::Point2d>& pts) {
  if (pts.size() < 3) throw InputError("a circle needs at least 3 points");
  // Centre the data for conditioning.
  cv::Point2d m(0, 0);
  for (const auto& p : pts) m += p;
  m *= 1.0 / static_cast<double>(pts.size());
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& p : pts) {
    const double x = p.x - m.x, y = p.y - m.y;
    const Eigen::Vector3d r(x, y, 1.0);
    A += r * r.transpose();
    b += r * (-(x * x + y * y));
  }
  const Eigen::Vector3d s = A.ldlt().solve(b);
  const double cx = -0.5 * s(0), cy = -0.5 * s(1);
  const double r2 = cx * cx + cy * cy - s(2);
  if (!(r2 > 0)) throw InputError("the centreline is not ring-shaped (circle fit failed)");
  return {cx + m.x, cy + m.y, std::sqrt(r2)};
}

double view_angle(cv::Point2d p, cv::Point2d c) {
  double a = std::atan2(-(p.y - c.y), p.x - c.x);
  if (a < 0) a += 2 * M_PI;
  return a;
}

std::vector<TimedWidth> map_constant_speed(const std::vector<double>& s_mm, const std::vector<double>& width_mm,
                                           const std::vector<double>& confidence, double speed_mm_s,
                                           double setpoint_width_mm) {
  if (!(speed_mm_s > 0)) throw InputError("the print speed must be > 0 mm/s");
  std::vector<TimedWidth> rows;
  for (std::size_t i = 0; i < s_mm.size(); ++i) {
    if (!std::isfinite(width_mm[i])) continue;
    rows.push_back({s_mm[i] / speed_mm_s, s_mm[i], width_mm[i], setpoint_width_mm, confidence[i]});
  }
  return rows;
}

double feed_setpoint_width_mm(const PathSegment& seg, double filament_diameter_mm, double layer_height_mm) {
  if (!(seg.length_mm > 0) || !(layer_height_mm > 0)) return std::numeric_limits<double>::quiet_NaN();
  const double area = M_PI * 0.25 * filament_diameter_mm * filament_diameter_mm;
  return seg.feed_mm * area / (seg.length_mm * layer_height_mm);
}

namespace {

// Each row's set-point as the mean of the commanded set-point over the row's window, from
// half-way to the previous sample to half-way to the next (in time; the first and the last row
// mirror their one neighbour). A width sample is the bead averaged over its pixel's extent along
// the line, about that window: where the feed changes inside it, the sample shows part of the new
// level. The set-point taken at the sample's centre alone would put the change at a sample, and
// the printed line test's changes fall at the same phase of the pixel grid on every line (whole
// millimetres on a grid of 1/12 mm), so a step fit that assumes the change half-way between two
// samples read the dead time half a sample (2 ms at 20 mm/s) long on every line alike. With the
// window means the change sits inside its window where the record says (InputHold::centred).
void window_mean_setpoints(std::vector<TimedWidth>& rows, const std::vector<PathSegment>& path,
                           const std::vector<double>& t0, const PathMapping& how) {
  if (rows.size() < 2) return;
  std::vector<double> w(path.size()), area(path.size() + 1, 0.0);  // area: integral of the set-point dt
  for (std::size_t k = 0; k < path.size(); ++k) {
    w[k] = feed_setpoint_width_mm(path[k], how.filament_diameter_mm, how.layer_height_mm);
    area[k + 1] = area[k] + (std::isfinite(w[k]) ? w[k] * (t0[k + 1] - t0[k]) : 0.0);
  }
  auto integral = [&](double t) {
    t = std::clamp(t, 0.0, t0.back());
    const auto k = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(
        std::upper_bound(t0.begin(), t0.end(), t) - t0.begin() - 1, 0, static_cast<std::ptrdiff_t>(path.size()) - 1));
    return area[k] + (std::isfinite(w[k]) ? w[k] * (t - t0[k]) : 0.0);
  };
  const std::size_t n = rows.size();
  std::vector<double> mean(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double left = i > 0 ? rows[i].t_s - rows[i - 1].t_s : rows[1].t_s - rows[0].t_s;
    const double right = i + 1 < n ? rows[i + 1].t_s - rows[i].t_s : rows[n - 1].t_s - rows[n - 2].t_s;
    const double a = std::max(0.0, rows[i].t_s - 0.5 * left), b = std::min(t0.back(), rows[i].t_s + 0.5 * right);
    mean[i] = b > a ? (integral(b) - integral(a)) / (b - a) : rows[i].setpoint_mm;
  }
  for (std::size_t i = 0; i < n; ++i)
    if (std::isfinite(mean[i])) rows[i].setpoint_mm = mean[i];
}

}  // namespace

std::vector<TimedWidth> map_path(const std::vector<double>& s_mm, const std::vector<double>& width_mm,
                                 const std::vector<double>& confidence, const std::vector<PathSegment>& path,
                                 const PathMapping& how) {
  double total = 0;
  for (const auto& p : path) {
    if (!(p.length_mm >= 0) || !(p.speed_mm_s > 0))
      throw InputError("path segments need a length >= 0 and a speed > 0");
    total += p.length_mm;
  }
  if (path.empty() || !(total > 0)) throw InputError("the commanded path is empty (no extruding moves)");
  const bool from_feed = how.filament_diameter_mm > 0 && how.layer_height_mm > 0;
  const double filament_area = M_PI * 0.25 * how.filament_diameter_mm * how.filament_diameter_mm;
  if (!from_feed && !(how.setpoint_width_mm > 0))
    throw InputError("a set-point width is needed: filament diameter and layer height, or a constant width");
  const double len = s_mm.empty() ? 0.0 : s_mm.back() - s_mm.front();
  const double offset = std::isfinite(how.offset_mm) ? how.offset_mm : 0.5 * (total - len);
  // Cumulative path length and time at each segment start.
  std::vector<double> s0(path.size() + 1, 0.0), t0(path.size() + 1, 0.0);
  for (std::size_t i = 0; i < path.size(); ++i) {
    s0[i + 1] = s0[i] + path[i].length_mm;
    t0[i + 1] = t0[i] + path[i].length_mm / path[i].speed_mm_s;
  }
  std::vector<TimedWidth> rows;
  for (std::size_t i = 0; i < s_mm.size(); ++i) {
    if (!std::isfinite(width_mm[i])) continue;
    const double along = how.reversed ? (s_mm.back() - s_mm[i]) : (s_mm[i] - s_mm.front());
    const double sp = offset + along;
    if (sp < 0 || sp > total) continue;
    const auto k = static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(
        std::upper_bound(s0.begin(), s0.end(), sp) - s0.begin() - 1, 0, static_cast<std::ptrdiff_t>(path.size()) - 1));
    const double t = t0[k] + (sp - s0[k]) / path[k].speed_mm_s;
    const double w_sp = from_feed ? feed_setpoint_width_mm(path[k], how.filament_diameter_mm, how.layer_height_mm)
                                  : how.setpoint_width_mm;
    TimedWidth row{t, sp, width_mm[i], w_sp, confidence[i]};
    if (from_feed) row.feed_per_width = how.layer_height_mm * path[k].speed_mm_s / filament_area;
    rows.push_back(row);
  }
  std::sort(rows.begin(), rows.end(), [](const TimedWidth& a, const TimedWidth& b) { return a.t_s < b.t_s; });
  rows.erase(
      std::unique(rows.begin(), rows.end(), [](const TimedWidth& a, const TimedWidth& b) { return !(b.t_s > a.t_s); }),
      rows.end());
  if (from_feed) window_mean_setpoints(rows, path, t0, how);
  return rows;
}

std::string timed_width_csv(const std::vector<TimedWidth>& rows, const std::string& comment) {
  std::ostringstream o;
  std::istringstream c(comment);
  for (std::string line; std::getline(c, line);) o << "# " << line << "\n";
  const bool feeds = !rows.empty() && std::all_of(rows.begin(), rows.end(), [](const TimedWidth& r) {
    return std::isfinite(r.feed_per_width) && r.feed_per_width > 0;
  });
  o << "time (s),s (mm),width (mm),setpoint_width (mm),confidence"
    << (feeds ? ",feed (mm/s),delivered_feed (mm/s)\n" : "\n");
  for (const auto& r : rows) {
    o << fmt::format("{:.9g},{:.9g},{:.9g},{:.9g},{:.4f}", r.t_s, r.s_mm, r.width_mm, r.setpoint_mm, r.confidence);
    if (feeds) o << fmt::format(",{:.9g},{:.9g}", r.setpoint_mm * r.feed_per_width, r.width_mm * r.feed_per_width);
    o << "\n";
  }
  return o.str();
}

}  // namespace tunekit::vision
