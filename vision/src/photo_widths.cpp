// measure_photo_widths: scale (photo_scale.cpp), features (measure_line_widths), their profiles
// in mm, then the printed tests the caller describes (photo_tests.cpp).

#include "tunekit/vision/photo_widths.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "photo_widths_stages.hpp"
#include "tunekit/core/error.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::vision {
namespace {

// In a photo of the printed tests, features shorter than 20 mm are not the tests (their lines
// are 150 mm, the ring's circumference about 190 mm) but travel strings, blobs and purge
// strokes; the floor is applied on top of the detector's own minimum length (px).
constexpr double kMinTestFeatureMm = 20;

CalibratedLine calibrate_line(const MeasuredLine& l, double ppm) {
  CalibratedLine c;
  std::vector<double> valid;
  for (const auto& s : l.samples) {
    c.s_mm.push_back(s.s_px / ppm);
    c.width_mm.push_back(s.valid() ? s.width_px / ppm : std::numeric_limits<double>::quiet_NaN());
    c.confidence.push_back(s.confidence);
    if (s.valid()) valid.push_back(s.width_px / ppm);
  }
  c.mean_mm = l.mean_width_px / ppm;
  c.std_mm = l.std_width_px / ppm;
  c.median_mm = valid.empty() ? std::numeric_limits<double>::quiet_NaN() : fitting::median(valid);
  c.length_mm = l.length_px / ppm;
  return c;
}

// The nominal width of the longest line as the scale, when nothing better was given.
void scale_from_nominal_width(PhotoWidths& out, double nominal_mm) {
  const auto& lines = out.features.lines;
  if (lines.empty() || !(lines.front().valid_samples > 0)) {
    out.failure = "scale target not found: no line of the reference width was measured";
    return;
  }
  out.scale = {ScaleSource::nominal_width,
               lines.front().mean_width_px / nominal_mm,
               fmt::format("reference width {} mm (line 1)", nominal_mm),
               "nothing else gives the scale: the longest line is taken to have its nominal width",
               {}};
}

LineWidthOptions detection_options(const PhotoWidthsRequest& req, const PhotoWidths& out) {
  LineWidthOptions opt = req.detection;
  if (!out.target_outline.empty()) {
    opt.exclude_mask = cv::Mat::zeros(out.measured.size(), CV_8U);
    cv::fillConvexPoly(opt.exclude_mask, out.target_outline, cv::Scalar(255));
  }
  const bool printed_test = req.line_test || req.ring_test;
  if (printed_test && out.scale.px_per_mm > 0)
    opt.min_length_px = std::max(opt.min_length_px, kMinTestFeatureMm * out.scale.px_per_mm);
  return opt;
}

void measure_printed_tests(PhotoWidths& out, const PhotoWidthsRequest& req) {
  if (req.line_test) detail::measure_line_test(out, *req.line_test, req.placement);
  if (!req.ring_test) return;
  const int ring = detail::find_ring_feature(out.features);
  if (ring < 0) {
    out.warnings.push_back("no ring found in the photo: no gain and phase from the ring test");
    return;
  }
  out.ring = measure_ring(out.features.lines[static_cast<std::size_t>(ring)], out.scale.px_per_mm, *req.ring_test,
                          out.warnings);
  if (out.ring) out.ring->feature = static_cast<std::size_t>(ring);
}

void check_request(const PhotoWidthsRequest& req) {
  const auto& s = req.scale;
  const bool any_scale =
      s.chessboard || s.charuco || (s.camera && s.camera->has_bed_plane) || s.px_per_mm > 0 || s.nominal_width_mm > 0;
  if (!any_scale) throw InputError("no scale: give a board in the photo, a camera bed plane, px/mm or a line width");
  if (req.line_test && req.line_test->lines.empty()) throw InputError("the line test has no lines");
  if (req.ring_test && !(req.ring_test->sines > 0 && req.ring_test->speed_mm_s > 0))
    throw InputError("the ring test needs its sines per turn and its print speed (> 0)");
}

}  // namespace

PhotoWidths measure_photo_widths(const cv::Mat& photo, const PhotoWidthsRequest& req, const std::string& origin) {
  check_request(req);
  auto scaled = detail::scale_photo(photo, req.scale, origin);
  PhotoWidths out;
  out.measured = scaled.image;
  out.scale = std::move(scaled.choice);
  out.target_outline = std::move(scaled.outline);
  out.failure = std::move(scaled.failure);
  if (!out.failure.empty()) return out;
  out.features = measure_line_widths(out.measured, detection_options(req, out));
  for (const auto& w : out.features.warnings) out.warnings.push_back(w);
  if (out.scale.source == ScaleSource::none) scale_from_nominal_width(out, req.scale.nominal_width_mm);
  if (!out.failure.empty()) return out;
  for (const auto& l : out.features.lines) out.lines.push_back(calibrate_line(l, out.scale.px_per_mm));
  if (!out.features.lines.empty()) measure_printed_tests(out, req);
  return out;
}

}  // namespace tunekit::vision
