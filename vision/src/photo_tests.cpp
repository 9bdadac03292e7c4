// The printed tests of measure_photo_widths: the line test (widths along each straight line's
// commanded path, mapped to time) and the ring test (gain and phase of the width against the
// set-point at the ring's frequency; Holtrup, Tuning liquefier dynamics, MSc thesis, University
// of Twente, 2019, section 4.3.3).

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "photo_widths_stages.hpp"
#include "ring_geometry.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::vision {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// A line of the line test is a long thin bar along X: its box is more than 5 times as wide as
// high (a 0.5 mm bead over 150 mm is 300 times; a ring, blob or purge stroke is not).
constexpr double kStraightMinAspect = 5;
// A ring's box is about square; an open feature whose box is within 3:1 either way is a ring
// the detector cut open (e.g. where its end meets its start), not a line.
constexpr double kRingMaxAspect = 3;
// Where the camera's placement is unknown, the line is placed by its far end, whose bead width
// is read over the last 5 mm (several bead widths: a stable median, yet short of the step).
constexpr double kEndWindowMm = 5;
// Each line's lead-in is left out but for its last third, at most its last 15 mm: before that
// the nozzle is still recovering from the travel move and the prime (a restart, not the step under
// test); the rest is the settled level before the step (15 mm: 0.75 s and 180 samples at the line
// test's 20 mm/s and 12 px/mm). A longer lead-in (calibrate prints 90 mm) gives a slow liquefier
// more time to settle, not more record.
constexpr double kLeadKeptFraction = 1.0 / 3.0;
constexpr double kLeadKeptMaxMm = 15;
// Each line's last 5 mm are left out too: there the nozzle stops (v^2 / 2a = 0.2 mm at the line
// test's 20 mm/s and 1000 mm/s^2) while the melt still flows, and the bead ends in its cap; the
// width read there is the stop, not the level (0.6 % wide over the last 5 mm of a 195 mm line).
constexpr double kLineEndSkipMm = 5;
// A line that starts from rest keeps its run-up from half-way on: the first half holds the nozzle's
// start and, on a printer, the ooze of the wait before it at the run-up's start.
constexpr double kRunupKeptFrom = 0.5;
// Fewer samples on the path than this (a few mm at 12 px/mm) cannot show a step response.
constexpr std::size_t kMinLineSamples = 20;
// Ring samples before this angle (rad) are left out: the liquefier is still filling after the
// travel move that precedes the ring (about 2.5 rad at the ring test's speed and radius covers
// three time constants of a typical hot end).
constexpr double kRingSkipRad = 2.5;
// ... and the last 0.05 rad (1.5 mm on a 30 mm ring), where the ring's end runs into its start.
constexpr double kRingEndSkipRad = 0.05;
// The sine fit (offset, drift, cosine, sine: four terms) needs well over a period's worth of
// samples: fewer than 50 are not a measurement.
constexpr std::size_t kMinRingSamples = 50;

double aspect_wide(const cv::Rect& b) { return static_cast<double>(b.width) / std::max(1, b.height); }

// The sines fitted to the ring: its fundamental and the next three harmonics (k w, k = 1..4). A
// liquefier whose time constant changes with the flow answers a +-30 % sine with a few per cent at
// 2w and 3w; fitted, they neither leak into the fundamental over the ring's part turn nor count as
// noise in its interval.
constexpr int kRingHarmonics = 4;

// y ~ a0 + a1 t + sum_k c_k cos(k w t) + s_k sin(k w t): the complex amplitude c_1 - j s_1 at w,
// the mean level a0 + a1 mean(t), and the covariance of (level, real, imaginary). The residuals
// (the photo's noise, the bead's ripple) are correlated along the ring: the least-squares
// covariance is scaled by their variance factor (fitting::residual_variance_factor, Bartlett
// 1935), and the degrees of freedom are those of the effective number of independent samples.
struct SineFit {
  std::complex<double> amplitude;
  double level = 0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< of (level, real, imaginary)
  double dof = 0;
};

SineFit sine_fit(const std::vector<double>& t, const std::vector<double>& y, double w) {
  const auto n = static_cast<Eigen::Index>(t.size());
  constexpr Eigen::Index p = 2 + 2 * kRingHarmonics;
  Eigen::MatrixXd A(n, p);
  Eigen::VectorXd b(n);
  double t_mean = 0;
  for (Eigen::Index r = 0; r < n; ++r) {
    const double ti = t[static_cast<std::size_t>(r)];
    t_mean += ti / static_cast<double>(n);
    A(r, 0) = 1;
    A(r, 1) = ti;
    for (int k = 1; k <= kRingHarmonics; ++k) {
      A(r, 2 * k) = std::cos(k * w * ti);
      A(r, 2 * k + 1) = std::sin(k * w * ti);
    }
    b(r) = y[static_cast<std::size_t>(r)];
  }
  const Eigen::VectorXd x = fitting::least_squares_solve(A, b);
  const Eigen::VectorXd res = b - A * x;
  const std::vector<double> rv(res.data(), res.data() + n);
  const double factor = fitting::residual_variance_factor(rv);
  const Eigen::MatrixXd C =
      (res.squaredNorm() / static_cast<double>(n - p)) * factor * fitting::inverse(A.transpose() * A);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, p);  // (level, real, imaginary) from the coefficients
  J(0, 0) = 1;
  J(0, 1) = t_mean;
  J(1, 2) = 1;
  J(2, 3) = -1;
  SineFit f;
  f.amplitude = {x(2), -x(3)};
  f.level = x(0) + x(1) * t_mean;
  f.covariance = J * C * J.transpose();
  f.dof = std::max(1.0, static_cast<double>(n) / factor - static_cast<double>(p));
  return f;
}

// The ring's gain is that of the width's relative modulation, amplitude over mean width, over the
// set-point's: the response at f over the steady response. A photo's scale (px/mm from a
// chessboard or a nominal width) and the extrusion multiplier both scale the mean width and the
// amplitude alike, so they cancel from it; an absolute ratio would carry their per-cent errors,
// which no interval from the photo's noise includes. The phase is the measured sine's less the
// set-point's. Standard errors by the delta method (the set-point is known exactly).
void ring_gain_phase(const SineFit& m, const SineFit& sp, RingResult& r) {
  const std::complex<double> H = (m.amplitude / m.level) / (sp.amplitude / sp.level);
  r.gain = std::abs(H);
  r.phase_deg = std::arg(H) * 180 / std::numbers::pi;
  const double a = m.amplitude.real(), b = m.amplitude.imag(), mag2 = std::norm(m.amplitude);
  // Gradients over (level, real, imaginary) of ln(gain) and of the phase (rad).
  const Eigen::Vector3d d_ln_gain(-1 / m.level, a / mag2, b / mag2), d_arg(0, -b / mag2, a / mag2);
  r.gain_stderr = r.gain * std::sqrt(d_ln_gain.dot(m.covariance * d_ln_gain));
  r.phase_stderr_deg = std::sqrt(d_arg.dot(m.covariance * d_arg)) * 180 / std::numbers::pi;
  const double k = fitting::t_multiplier(0.95, m.dof);
  r.gain_ci95 = {r.gain - k * r.gain_stderr, r.gain + k * r.gain_stderr};
  r.phase_ci95_deg = {r.phase_deg - k * r.phase_stderr_deg, r.phase_deg + k * r.phase_stderr_deg};
  r.mean_width_mm = m.level;
}

// Valid samples of a straight line as (position on its path, width, confidence), by position.
struct PathSamples {
  std::vector<double> s, w, c;
};

// Where a photo column lies on a line's path (mm from the path's start) and back: by the camera's
// placement, or without it by the line's far end (the nozzle stopped at the path's end, the bead
// ends half a width beyond it).
struct PathPlacement {
  bool by_camera = false;
  double a = 0, ppm = 1;  ///< pos = a + x_px / ppm
  double length_mm = 0;   ///< the path's length
  double pos(double x_px) const { return a + x_px / ppm; }
  double x_px(double pos_mm) const { return (pos_mm - a) * ppm; }
};

PathPlacement path_placement(const MeasuredLine& ml, const TestLine& tl, double ppm, const BedPlacement& placement) {
  PathPlacement p;
  p.ppm = ppm;
  p.by_camera = placement.known;
  for (const auto& sg : tl.path) p.length_mm += sg.length_mm;
  if (placement.known) {
    p.a = placement.x0_mm + 0.5 / ppm - tl.x0_mm;
    return p;
  }
  const double x_end_px = ml.bbox.x + ml.bbox.width - 0.5;
  std::vector<double> end_widths;
  for (const auto& s : ml.samples)
    if (s.valid() && s.x_px > x_end_px + 0.5 - kEndWindowMm * ppm) end_widths.push_back(s.width_px);
  const double w_end_px = fitting::median(end_widths);
  p.a = p.length_mm - (x_end_px - w_end_px / 2) / ppm;
  return p;
}

// A line whose path begins with a run-up (no extrusion) starts from rest: its record keeps the
// run-up's second half (the first holds the nozzle's start and, on a printer, the ooze of the
// wait before it) and the whole lead-in, the thin start measured by its integrated contrast
// (start_widths). Returns false (and why) when the start cannot be measured.
bool from_rest_samples(const cv::Mat& img, const MeasuredLine& ml, const TestLine& tl, const PathPlacement& pp,
                       std::vector<std::array<double, 3>>& rows, std::string& why) {
  const double runup = tl.path.front().length_mm;
  const double keep_from = kRunupKeptFrom * runup;
  const auto start = detail::start_widths(img, ml, pp.ppm, pp.x_px(keep_from), &why);
  if (!start) return false;
  std::vector<double> conf;
  for (const auto& s : ml.samples)
    if (s.valid()) conf.push_back(s.confidence);
  const double c = fitting::median(conf);
  for (std::size_t i = 0; i < start->x_px.size(); ++i)
    rows.push_back({pp.pos(start->x_px[i]), start->width_px[i] / pp.ppm, c});
  for (const auto& s : ml.samples)
    if (s.valid() && s.x_px >= start->edge_fit_from_px && pp.pos(s.x_px) >= keep_from)
      rows.push_back({pp.pos(s.x_px), s.width_px / pp.ppm, s.confidence});
  return true;
}

PathSamples on_path(const cv::Mat& img, const MeasuredLine& ml, const TestLine& tl, double ppm,
                    const BedPlacement& placement, std::vector<std::string>& warnings, std::size_t k) {
  const PathPlacement pp = path_placement(ml, tl, ppm, placement);
  const bool runup = tl.path.size() > 1 && tl.path.front().feed_mm == 0;
  std::vector<std::array<double, 3>> rows;
  std::string why;
  // Placed by its far end, a line's position along its path is known only to about the dead time
  // times the speed (the bead's end is where the melt stopped, not the nozzle), and the area of a
  // start from rest moves by the level times that time: its start is then left out like a restart.
  if (!(runup && pp.by_camera && from_rest_samples(img, ml, tl, pp, rows, why))) {
    if (runup && pp.by_camera)
      warnings.push_back(
          fmt::format("line {}: its start from rest was not measured ({}); its lead-in is left out", k + 1, why));
    rows.clear();
    const double before = runup ? tl.path.front().length_mm : 0.0;
    const double lead = tl.path[runup ? 1 : 0].length_mm;
    const double lead_skip = before + lead - std::min(kLeadKeptFraction * lead, kLeadKeptMaxMm);
    for (const auto& s : ml.samples)
      if (s.valid() && pp.pos(s.x_px) >= lead_skip) rows.push_back({pp.pos(s.x_px), s.width_px / ppm, s.confidence});
  }
  std::erase_if(rows, [&](const auto& r) { return r[0] > pp.length_mm - kLineEndSkipMm; });
  std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a[0] < b[0]; });
  PathSamples out;
  for (const auto& r : rows) out.s.push_back(r[0]), out.w.push_back(r[1]), out.c.push_back(r[2]);
  return out;
}

std::vector<std::size_t> straight_lines(const LineWidthResult& features) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < features.lines.size(); ++i) {
    const auto& l = features.lines[i];
    if (!l.closed && aspect_wide(l.bbox) > kStraightMinAspect) idx.push_back(i);
  }
  // Printed first = highest Y = topmost in the photo.
  std::sort(idx.begin(), idx.end(),
            [&](auto a, auto b) { return features.lines[a].bbox.y < features.lines[b].bbox.y; });
  return idx;
}

}  // namespace

namespace detail {

int find_ring_feature(const LineWidthResult& features) {
  for (std::size_t i = 0; i < features.lines.size(); ++i)
    if (looks_like_ring(features.lines[i])) return static_cast<int>(i);
  return -1;
}

void measure_line_test(PhotoWidths& out, const LineTest& test, const BedPlacement& placement) {
  const double ppm = out.scale.px_per_mm;
  const auto straight = straight_lines(out.features);
  if (straight.empty()) {
    out.failure = fmt::format(
        "the photo shows {} printed feature(s) but none of the line test's straight lines along X (photograph "
        "with the bed's X axis to the right)",
        out.features.lines.size());
    return;
  }
  if (straight.size() != test.lines.size())
    out.warnings.push_back(
        fmt::format("the photo shows {} of the {} printed lines; the first {} are used in print order", straight.size(),
                    test.lines.size(), std::min(straight.size(), test.lines.size())));
  for (std::size_t k = 0; k < std::min(straight.size(), test.lines.size()); ++k) {
    const auto& ml = out.features.lines[straight[k]];
    const auto ps = on_path(out.measured, ml, test.lines[k], ppm, placement, out.warnings, k);
    if (ps.s.size() < kMinLineSamples) {
      out.warnings.push_back(fmt::format("line {}: too few measured samples on the path", k + 1));
      continue;
    }
    PathMapping how;
    how.offset_mm = ps.s.front();  // map_path counts along the profile from its first sample
    how.filament_diameter_mm = test.filament_diameter_mm;
    how.layer_height_mm = test.layer_height_mm;
    LineTestResult r;
    r.feature = straight[k];
    r.rows = map_path(ps.s, ps.w, ps.c, test.lines[k].path, how);
    double sum = 0;
    for (const auto& row : r.rows) sum += row.width_mm;
    r.mean_width_mm = r.rows.empty() ? 0 : sum / static_cast<double>(r.rows.size());
    r.median_width_mm = out.lines[straight[k]].median_mm;
    r.placed_by_camera = placement.known;
    out.line_test.push_back(std::move(r));
  }
  if (out.line_test.empty()) out.failure = "no usable width samples on the printed lines";
}

}  // namespace detail

bool looks_like_ring(const MeasuredLine& l) {
  const double a = aspect_wide(l.bbox);
  return l.closed || (a < kRingMaxAspect && a > 1 / kRingMaxAspect);
}

namespace {

// The ring's samples past its start, against time, with their set-point (r: centre and radii).
std::vector<TimedWidth> ring_rows(const std::vector<cv::Point2d>& pts, const std::vector<double>& widths,
                                  const std::vector<double>& conf, const RingTest& ring, const RingResult& r) {
  const double a_sp =
      ring.setpoint_amplitude_mm > 0 ? ring.setpoint_amplitude_mm : ring.setpoint_amplitude_mm2 / r.radius_mm;
  const double start = ring.start_deg * std::numbers::pi / 180,
               phase = ring.setpoint_phase_deg * std::numbers::pi / 180;
  std::vector<TimedWidth> rows;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    double th = view_angle(pts[i], r.centre_px) - start;
    if (ring.clockwise) th = -th;
    th = std::fmod(th, kTwoPi);
    if (th < 0) th += kTwoPi;
    if (th < kRingSkipRad || th > kTwoPi - kRingEndSkipRad) continue;
    double th_sp = th;  // the set-point is constant along each segment: its value at the middle
    if (ring.segments > 0)
      th_sp = kTwoPi * (std::clamp(std::floor(th / kTwoPi * ring.segments), 0.0, ring.segments - 1.0) + 0.5) /
              ring.segments;
    rows.push_back({th * r.radius_mm / ring.speed_mm_s, th * r.radius_mm, widths[i],
                    ring.setpoint_width_mm + a_sp * std::sin(ring.sines * th_sp + phase), conf[i]});
  }
  std::sort(rows.begin(), rows.end(), [](const auto& p, const auto& q) { return p.t_s < q.t_s; });
  // Equal times (two samples at the same angle) would break a strictly increasing time column.
  rows.erase(std::unique(rows.begin(), rows.end(), [](const auto& p, const auto& q) { return !(q.t_s > p.t_s); }),
             rows.end());
  return rows;
}

}  // namespace

std::optional<RingResult> measure_ring(const MeasuredLine& feature, double ppm, const RingTest& ring,
                                       std::vector<std::string>& warnings) {
  std::vector<cv::Point2d> pts;
  std::vector<double> widths, conf;
  for (const auto& s : feature.samples)
    if (s.valid()) pts.emplace_back(s.x_px, s.y_px), widths.push_back(s.width_px / ppm), conf.push_back(s.confidence);
  if (pts.size() < kMinRingSamples) {
    warnings.push_back("the ring was not measured (too few valid samples)");
    return std::nullopt;
  }
  RingResult r;
  const cv::Vec3d c = fit_circle(pts);
  r.centre_px = {c[0], c[1]};
  r.measured_radius_mm = c[2] / ppm;
  r.radius_mm = ring.radius_mm > 0 ? ring.radius_mm : r.measured_radius_mm;
  r.rows = ring_rows(pts, widths, conf, ring, r);
  if (r.rows.size() < kMinRingSamples) {
    warnings.push_back("the ring has too few measured samples past its start for gain and phase");
    return std::nullopt;
  }
  std::vector<double> t, y, ysp;
  for (const auto& row : r.rows) t.push_back(row.t_s), y.push_back(row.width_mm), ysp.push_back(row.setpoint_mm);
  const double w = ring.sines * ring.speed_mm_s / r.radius_mm;
  const auto m = sine_fit(t, y, w), sp = sine_fit(t, ysp, w);
  r.freq_hz = w / kTwoPi;
  ring_gain_phase(m, sp, r);
  r.samples = t.size();
  r.setpoint_amplitude_mm = std::abs(sp.amplitude);
  r.width_amplitude_mm = std::abs(m.amplitude);
  r.skipped_start_rad = kRingSkipRad;
  return r;
}

nlohmann::json to_json(const RingResult& r) {
  return {{"freq_hz", r.freq_hz},
          {"gain", r.gain},
          {"gain_stderr", r.gain_stderr},
          {"gain_ci95", r.gain_ci95},
          {"phase_deg", r.phase_deg},
          {"phase_stderr_deg", r.phase_stderr_deg},
          {"phase_ci95_deg", r.phase_ci95_deg},
          {"samples", r.samples},
          {"radius_mm", r.radius_mm},
          {"measured_radius_mm", r.measured_radius_mm},
          {"mean_width_mm", r.mean_width_mm},
          {"setpoint_amplitude_mm", r.setpoint_amplitude_mm},
          {"width_amplitude_mm", r.width_amplitude_mm}};
}

}  // namespace tunekit::vision
