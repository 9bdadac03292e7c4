// A line's start from rest: widths where the bead is thinner than the edge fit can measure, or
// not there yet. The edge fit (line_edge_profile.cpp) needs a bar at least a pixel wide whose
// blur is below half its width; the start of a line printed from rest rises from no bead at all.
// Across the line, the light a bead adds to the bed's is its contrast times its width (the blur
// spreads it but keeps its sum), so the width is the profile's integral above the bed over the
// contrast per unit width, and that ratio is read on the same line where both measurements hold.

#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Dense>

#include "line_width_stages.hpp"
#include "photo_widths_stages.hpp"
#include "tunekit/fitting/dense_solvers.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::vision::detail {
namespace {

// The centreline is the straight line fitted to the edge fit's centres over the first 20 mm of
// the measured bead (a line of the line test runs straight along X; further on, a camera's
// residual distortion bends its image a little).
constexpr double kCentrelineFitMm = 20;
// Across the line the profile is summed over +-(w / 2 + 4 px), w the line's median width: the bead
// at its median width and 4 blur sigmas of a focused camera's edge spread (1 px) beyond each edge,
// and no wider, as every pixel summed adds its noise. The bed's level under it is the straight line
// through the means of the 8 px beyond each end (its noise enters every pixel summed: fewer bed
// pixels made it the larger part of the width's noise). Each width is the mean over 3 columns,
// about the edge fit's averaging along the line.
constexpr double kStartHalfWindowPerWidth = 0.5;
constexpr double kStartHalfWindowMarginPx = 4.0;
constexpr int kBedBandPx = 8;
constexpr int kAlongHalfPx = 1;
// The edge fit takes over after the last of its widths below 80 % of the line's median within
// the bead's first 30 mm (a slow liquefier's rise from rest to 80 % takes 1.6 time constants, 15 mm
// at 0.45 s and 20 mm/s): beyond that the bar is several pixels wide and its edges are well
// determined. On the thin start the edge fit reads a bead of 2-4 px a few per cent narrow, and an
// occasional sample there reads 80 % wide.
constexpr double kEdgeFitFromShare = 0.8;
constexpr double kRiseSearchMm = 30;
// The contrast per unit width is read on the edge fit's samples within 10 % of the line's median
// width over the 30 mm from there on (settled, where the edge fit is exact), as a quadratic in the
// position along the line, and extrapolated back over the start: the light falls towards the
// photo's edges (vignetting; a line's start is near one), and with it the contrast, by 14 % over
// the first 15 mm of a line starting 9 mm from the frame's edge on the simulated camera.
constexpr double kContrastWidthShare = 0.1;
constexpr double kContrastWindowMm = 30;
// Fewer columns than this over the contrast window are not a calibration.
constexpr std::size_t kMinContrastColumns = 10;

// The image at (x, y) px, clamped to its border (the bed bands of a line near the frame's edge).
double at(const cv::Mat& img, double x, double y) {
  return bilinear(img, std::clamp(x, 0.0, img.cols - 1.0), std::clamp(y, 0.0, img.rows - 1.0));
}
// The profile's integral above the bed's level across the line at column x (image units x px).
double integrated_contrast(const cv::Mat& img, double x, double yc, int half) {
  double lo = 0, hi = 0;
  for (int k = 1; k <= kBedBandPx; ++k) lo += at(img, x, yc - half - k), hi += at(img, x, yc + half + k);
  lo /= kBedBandPx;
  hi /= kBedBandPx;
  const double span = 2.0 * half + kBedBandPx + 1;  // between the bands' centres
  double sum = 0;
  for (int k = -half; k <= half; ++k) {
    const double bed = lo + (hi - lo) * (k + half + 0.5 * (kBedBandPx + 1)) / span;
    sum += at(img, x, yc + k) - bed;
  }
  return sum;
}

// The centreline y = c0 + c1 x through the edge fit's centres over the bead's first 20 mm.
Eigen::Vector2d centreline(const std::vector<const WidthSample*>& valid, double ppm) {
  const double x_end = valid.front()->x_px + kCentrelineFitMm * ppm;
  std::size_t n = 0;
  while (n < valid.size() && valid[n]->x_px <= x_end) ++n;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(n), 2);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    A(k, 0) = 1, A(k, 1) = valid[i]->x_px, y(k) = valid[i]->y_px;
  }
  return fitting::least_squares_solve(A, y);
}

// The contrast per unit width along the line, c0 + c1 z + c2 z^2 with z in mm from x0, fitted to
// the settled samples' integrated contrast over their edge-fit width; nullopt with too few.
std::optional<Eigen::Vector3d> contrast_along(const cv::Mat& img, const std::vector<const WidthSample*>& valid,
                                              std::size_t from, const Eigen::Vector2d& cl, int half, double w_med,
                                              double ppm) {
  const double x0 = valid[from]->x_px;
  std::vector<std::array<double, 2>> zr;
  for (std::size_t i = from; i < valid.size() && valid[i]->x_px <= x0 + kContrastWindowMm * ppm; ++i) {
    const double x = valid[i]->x_px;
    if (std::abs(valid[i]->width_px - w_med) <= kContrastWidthShare * w_med)
      zr.push_back({(x - x0) / ppm, integrated_contrast(img, x, cl(0) + cl(1) * x, half) / valid[i]->width_px});
  }
  if (zr.size() < kMinContrastColumns) return std::nullopt;
  Eigen::MatrixXd Z(static_cast<Eigen::Index>(zr.size()), 3);
  Eigen::VectorXd r(static_cast<Eigen::Index>(zr.size()));
  for (std::size_t i = 0; i < zr.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    Z(k, 0) = 1, Z(k, 1) = zr[i][0], Z(k, 2) = zr[i][0] * zr[i][0], r(k) = zr[i][1];
  }
  return Eigen::Vector3d(fitting::least_squares_solve(Z, r));
}

}  // namespace

std::optional<StartWidths> start_widths(const cv::Mat& img, const MeasuredLine& ml, double ppm, double x_from_px,
                                        std::string* why) {
  auto refuse = [&](const char* reason) {
    if (why != nullptr) *why = reason;
    return std::optional<StartWidths>{};
  };
  std::vector<const WidthSample*> valid;
  std::vector<double> widths;
  for (const auto& s : ml.samples)
    if (s.valid()) valid.push_back(&s), widths.push_back(s.width_px);
  if (valid.size() < kMinContrastColumns || img.type() != CV_32F) return refuse("too few measured samples");
  std::sort(valid.begin(), valid.end(), [](auto a, auto b) { return a->x_px < b->x_px; });
  const double w_med = fitting::median(widths);
  const Eigen::Vector2d cl = centreline(valid, ppm);
  const int half = static_cast<int>(std::ceil(kStartHalfWindowPerWidth * w_med + kStartHalfWindowMarginPx));
  // Where the edge fit takes over: after its last width below 80 % of the median on the rise.
  std::size_t from = 0;
  for (std::size_t i = 0; i < valid.size() && valid[i]->x_px <= valid.front()->x_px + kRiseSearchMm * ppm; ++i)
    if (!(valid[i]->width_px >= kEdgeFitFromShare * w_med)) from = i + 1;
  if (from >= valid.size()) return refuse("the line never reaches its width");
  const auto cq = contrast_along(img, valid, from, cl, half, w_med, ppm);
  if (!cq) return refuse("too few settled samples to read the bead's contrast on");
  StartWidths out;
  out.edge_fit_from_px = valid[from]->x_px;
  out.contrast = (*cq)(0);
  for (double x = std::ceil(x_from_px); x < out.edge_fit_from_px; x += 1) {
    const double z = (x - out.edge_fit_from_px) / ppm, c = (*cq)(0) + (*cq)(1) * z + (*cq)(2) * z * z;
    if (!(c * out.contrast > 0)) return refuse("the bead's contrast does not extrapolate to the line's start");
    double sum = 0;
    for (int d = -kAlongHalfPx; d <= kAlongHalfPx; ++d)
      sum += integrated_contrast(img, x + d, cl(0) + cl(1) * (x + d), half);
    out.x_px.push_back(x);
    out.width_px.push_back(sum / (2 * kAlongHalfPx + 1) / c);
  }
  return out;
}

}  // namespace tunekit::vision::detail
