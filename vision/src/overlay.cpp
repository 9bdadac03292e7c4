#include "tunekit/vision/overlay.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "tunekit/core/error.hpp"
#include "tunekit/vision/image_io.hpp"

namespace tunekit::vision {

cv::Mat draw_overlay(const cv::Mat& image, const LineWidthResult* result, const std::vector<cv::Point>& target_outline,
                     const std::string& message) {
  cv::Mat g8;
  if (image.empty()) {
    g8 = cv::Mat(480, 640, CV_8U, cv::Scalar(0));
  } else {
    cv::Mat g = image;
    if (g.channels() == 3) cv::cvtColor(g, g, cv::COLOR_BGR2GRAY);
    if (g.channels() == 4) cv::cvtColor(g, g, cv::COLOR_BGRA2GRAY);
    double lo = 0, hi = 0;
    cv::minMaxLoc(g, &lo, &hi);
    const double sc = hi > lo ? 255.0 / (hi - lo) : 1.0;
    g.convertTo(g8, CV_8U, sc, -lo * sc);
  }
  cv::Mat out;
  cv::cvtColor(g8, out, cv::COLOR_GRAY2BGR);
  const int thick = std::max(1, std::min(out.cols, out.rows) / 800);
  const double font = std::max(0.5, std::min(out.cols, out.rows) / 1000.0);
  if (!target_outline.empty()) {
    std::vector<std::vector<cv::Point>> polys{target_outline};
    cv::polylines(out, polys, true, cv::Scalar(255, 128, 0), 2 * thick, cv::LINE_AA);
  }
  if (result) {
    int idx = 0;
    for (const auto& l : result->lines) {
      ++idx;
      const std::size_t n = l.samples.size();
      for (std::size_t i = 0; i < n; ++i) {
        const auto& s = l.samples[i];
        const cv::Point2d c(s.x_px, s.y_px);
        cv::Scalar col(0, 200, 0);
        if (s.flags & kFlagOutOfFrame) col = cv::Scalar(0, 0, 255);
        else if (s.flags & kFlagOccluded) col = cv::Scalar(0, 140, 255);
        else if (s.flags & kFlagMerged) col = cv::Scalar(255, 0, 255);
        if (i + 1 < n || l.closed) {
          const auto& t = l.samples[(i + 1) % n];
          cv::line(out, c, cv::Point2d(t.x_px, t.y_px), col, thick, cv::LINE_AA);
        }
        if (std::isfinite(s.width_px)) {
          const double h = 0.5 * s.width_px;
          const cv::Point2d a(c.x - h * s.nx, c.y - h * s.ny), b(c.x + h * s.nx, c.y + h * s.ny);
          out.at<cv::Vec3b>(std::clamp(static_cast<int>(std::lround(a.y)), 0, out.rows - 1),
                            std::clamp(static_cast<int>(std::lround(a.x)), 0, out.cols - 1)) = cv::Vec3b(255, 255, 0);
          out.at<cv::Vec3b>(std::clamp(static_cast<int>(std::lround(b.y)), 0, out.rows - 1),
                            std::clamp(static_cast<int>(std::lround(b.x)), 0, out.cols - 1)) = cv::Vec3b(255, 255, 0);
        }
      }
      if (n > 0) {
        const auto& s = l.samples[n / 2];
        cv::putText(out, fmt::format("{}", idx), cv::Point2d(s.x_px + 12 * font, s.y_px - 12 * font),
                    cv::FONT_HERSHEY_SIMPLEX, font, cv::Scalar(0, 255, 255), thick + 1, cv::LINE_AA);
      }
    }
  }
  if (!message.empty())
    cv::putText(out, message, cv::Point(10, static_cast<int>(30 * font)), cv::FONT_HERSHEY_SIMPLEX, 0.8 * font,
                cv::Scalar(0, 0, 255), thick + 1, cv::LINE_AA);
  return out;
}

void write_overlay(const std::string& path, const cv::Mat& bgr) { write_png(path, bgr); }

}  // namespace tunekit::vision
