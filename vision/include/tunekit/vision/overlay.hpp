#pragma once
// Check images for the line-width measurement: the photo with the detected edges (cyan),
// the centreline (green; flagged stretches orange = occluded, magenta = merged, red = out of
// frame), the line numbers, the scale target's outline and an optional message (an error).

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "tunekit/vision/line_width.hpp"

namespace tunekit::vision {

/// Draws on a colour copy of `image` (any depth/channels; contrast-stretched to 8 bit).
/// `result` may be null (nothing measured: only the target and message are drawn).
cv::Mat draw_overlay(const cv::Mat& image, const LineWidthResult* result, const std::vector<cv::Point>& target_outline,
                     const std::string& message);

/// Writes an overlay image as PNG (whatever the extension). Throws InputError when it cannot be written.
void write_overlay(const std::string& path, const cv::Mat& bgr);

}  // namespace tunekit::vision
