#pragma once
// Internal stages of measure_photo_widths (photo_widths.cpp): the scale (photo_scale.cpp) and
// the printed tests (photo_tests.cpp).

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "tunekit/vision/photo_widths.hpp"

namespace tunekit::vision::detail {

struct ScaledPhoto {
  cv::Mat image;  ///< grey CV_32F, undistorted, maybe rectified
  ScaleChoice choice;
  std::vector<cv::Point> outline;
  std::string failure;  ///< a board was asked for and not found
};

/// Undistorts and takes the first scale candidate that works (board, camera bed plane, stated).
ScaledPhoto scale_photo(const cv::Mat& photo, const ScaleCandidates& candidates, const std::string& origin);

/// The line test's lines among `out.features`, along their paths (fills out.line_test).
void measure_line_test(PhotoWidths& out, const LineTest& test, const BedPlacement& placement);

/// Widths of a line's start, from x_from_px (image column) up to where the edge fit's widths
/// first reach 80 % of the line's median (edge_fit_from_px): the bead's integrated contrast
/// across the line over its contrast per unit width, read where both hold (line_start.cpp).
struct StartWidths {
  std::vector<double> x_px, width_px;
  double edge_fit_from_px = 0;
  double contrast = 0;  ///< image units per px of width (signed as the bead's light)
};
std::optional<StartWidths> start_widths(const cv::Mat& img, const MeasuredLine& ml, double px_per_mm, double x_from_px,
                                        std::string* why);

/// Index of the ring among the features: the first closed or compact one; -1: none.
int find_ring_feature(const LineWidthResult& features);

}  // namespace tunekit::vision::detail
