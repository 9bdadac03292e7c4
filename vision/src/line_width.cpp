// Line width along printed beads (measure_line_widths): runs the stages of
// line_width_stages.hpp -- detection (line_detection.cpp), centreline (line_centreline.cpp),
// edge profile (line_edge_profile.cpp) -- and flags the samples that are outliers along a line.

#include "tunekit/vision/line_width.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "line_width_stages.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/core/file_bytes.hpp"
#include "tunekit/vision/image_io.hpp"

namespace tunekit::vision {
namespace {

using detail::kNaN;
using detail::median_of;

// Photos smaller than 16 px on a side hold no line whose width could be measured (the edge fit
// alone needs 10 samples across a line).
constexpr int kMinImageSidePx = 16;
// Mask components smaller than 8 coarse px, or than 1.5 px per px of the shortest line accepted
// (a line at least about 1.5 coarse px wide), cannot be such a line.
constexpr double kMinComponentAreaPx = 8.0;
constexpr double kMinComponentAreaPerLength = 1.5;
// Up to 4 candidate components per line asked for are traced: some turn out to be blobs, short
// or faint and are dropped.
constexpr int kCandidatesPerLine = 4;
// Outliers along a line. Occluded: less than 35 % of the line's median contrast (glare, dirt or
// a gap over the bead; a real bead keeps its contrast when its width changes), or a width
// standard error above a quarter of the width (no clean edges).
constexpr double kOccludedContrastFraction = 0.35;
constexpr double kOccludedRelStderr = 0.25;
// Merged: wider than 1.6 times the line's median width. Two touching beads measure about twice
// the median; the width changes a print test makes along one line stay well below 1.6 times it.
constexpr double kMergedWidthFactor = 1.6;
// Lines with a median contrast below this fraction of the strongest line's are not lines.
constexpr double kFaintFraction = 0.3;

}  // namespace

cv::Mat to_gray_float(const cv::Mat& image) {
  if (image.empty()) throw InputError("empty image");
  cv::Mat g;
  switch (image.channels()) {
    case 1: g = image; break;
    case 3: cv::cvtColor(image, g, cv::COLOR_BGR2GRAY); break;
    case 4: cv::cvtColor(image, g, cv::COLOR_BGRA2GRAY); break;
    default: throw InputError(fmt::format("unsupported image with {} channels", image.channels()));
  }
  cv::Mat f;
  g.convertTo(f, CV_32F);
  return f;
}

cv::Mat load_gray_image(const std::string& path) { return gray_image_from_bytes(read_file_bytes(path), path); }

cv::Mat gray_image_from_bytes(std::string_view bytes, const std::string& path) {
  const cv::Mat img = decode_image(bytes, path, ImageColor::keep);
  if (img.cols < kMinImageSidePx || img.rows < kMinImageSidePx)
    throw InputError(fmt::format("image too small ({}x{} px)", img.cols, img.rows), path);
  return to_gray_float(img);
}

void summarize_line(MeasuredLine& line) {
  double sum = 0, sum2 = 0;
  int n = 0;
  for (const auto& s : line.samples)
    if (s.valid()) {
      sum += s.width_px;
      sum2 += s.width_px * s.width_px;
      ++n;
    }
  line.valid_samples = n;
  line.mean_width_px = n > 0 ? sum / n : kNaN;
  line.std_width_px = n > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1))) : kNaN;
}

LineWidthResult measure_line_widths(const cv::Mat& gray_in, const LineWidthOptions& o) {
  if (gray_in.empty()) throw InputError("empty image");
  const cv::Mat gray = gray_in.type() == CV_32F ? gray_in : to_gray_float(gray_in);
  LineWidthResult res;
  res.width = gray.cols;
  res.height = gray.rows;
  const detail::Coarse c = detail::coarse_detect(gray, o, res.warnings);
  res.light_lines = c.light;
  res.coarse_factor = c.f;
  res.noise_sigma = c.noise;

  cv::Mat labels, stats, centroids;
  const int nlab = cv::connectedComponentsWithStats(c.mask, labels, stats, centroids, 8, CV_32S);
  std::vector<int> order;
  const double scale = 0.5 * (c.sx + c.sy);
  const double min_area = std::max(kMinComponentAreaPx, kMinComponentAreaPerLength * o.min_length_px / scale);
  for (int i = 1; i < nlab; ++i)
    if (stats.at<int>(i, cv::CC_STAT_AREA) >= min_area) order.push_back(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return stats.at<int>(a, cv::CC_STAT_AREA) > stats.at<int>(b, cv::CC_STAT_AREA); });
  if (static_cast<int>(order.size()) > kCandidatesPerLine * o.max_lines)
    order.resize(static_cast<std::size_t>(kCandidatesPerLine * o.max_lines));

  for (int lab : order) {
    std::optional<detail::Centreline> cl = detail::trace_centreline(c, labels, stats, lab, o);
    if (!cl) continue;
    MeasuredLine line;
    line.closed = cl->closed;
    line.bbox = cl->bbox;
    line.touches_frame = cl->touches_frame;

    const double half_window = detail::measuring_half_window(cl->w0);
    // Pass 1 (a subset of the stations): re-centre the centreline on the measured mid-points.
    detail::recentre_centreline(gray, c.light, *cl, half_window, o);
    // Pass 2: every station.
    const std::vector<detail::Station> st = detail::stations_from(cl->points, cl->closed);
    detail::measure_stations(gray, c.light, st, 1, half_window, o.along_half_px, cl->w0, line.samples);
    double s_acc = 0;
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (i > 0) s_acc += std::hypot(st[i].c.x - st[i - 1].c.x, st[i].c.y - st[i - 1].c.y);
      line.samples[i].s_px = s_acc;
    }
    line.length_px = s_acc;
    // Contrast and width outliers: occluded (faint) and merged (width jumps) stretches.
    std::vector<double> cs, ws;
    for (const auto& s : line.samples)
      if (s.valid()) {
        cs.push_back(s.contrast);
        ws.push_back(s.width_px);
      }
    if (ws.empty()) {
      summarize_line(line);
      res.lines.push_back(std::move(line));
      continue;
    }
    line.median_contrast = median_of(cs);
    const double wmed = median_of(ws);
    for (auto& s : line.samples) {
      if (!std::isfinite(s.width_px)) continue;
      if (s.contrast < kOccludedContrastFraction * line.median_contrast ||
          s.width_stderr_px > kOccludedRelStderr * s.width_px)
        s.flags |= kFlagOccluded;
      if (s.width_px > kMergedWidthFactor * wmed) s.flags |= kFlagMerged;
      if (s.flags & kFlagOccluded) s.width_px = kNaN;
    }
    summarize_line(line);
    res.lines.push_back(std::move(line));
    if (static_cast<int>(res.lines.size()) >= o.max_lines) break;
  }
  // Choose the lines by contrast: a feature far fainter than the strongest line is a shadow or a
  // lighting gradient the background model left behind (typically along the frame edge), not a
  // printed line.
  double strongest = 0;
  for (const auto& l : res.lines)
    if (l.valid_samples > 0) strongest = std::max(strongest, l.median_contrast);
  if (strongest > 0) {
    const auto faint = [&](const MeasuredLine& l) { return !(l.median_contrast >= kFaintFraction * strongest); };
    const auto dropped = std::count_if(res.lines.begin(), res.lines.end(), faint);
    if (dropped > 0) {
      res.lines.erase(std::remove_if(res.lines.begin(), res.lines.end(), faint), res.lines.end());
      res.warnings.push_back(
          fmt::format("ignored {} faint feature(s) with less than {:.0f} % of the strongest line's "
                      "contrast (shadows or uneven lighting, not lines)",
                      dropped, 100 * kFaintFraction));
    }
  }
  std::stable_sort(res.lines.begin(), res.lines.end(),
                   [](const MeasuredLine& a, const MeasuredLine& b) { return a.length_px > b.length_px; });
  return res;
}

}  // namespace tunekit::vision
