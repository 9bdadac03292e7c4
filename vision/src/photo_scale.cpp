// The scale stage of measure_photo_widths: undistort with the camera profile, then take the
// first scale candidate that works, in the order of ScaleSource (a board in this photo, the
// camera profile's bed plane, a stated px/mm; the nominal width of the longest line is applied
// after the lines are measured, photo_widths.cpp).

#include <cmath>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "photo_widths_stages.hpp"
#include "tunekit/core/error.hpp"

namespace tunekit::vision::detail {
namespace {

void find_board(ScaledPhoto& out, const ScaleCandidates& c) {
  ChessboardDetection det;
  std::string name;
  if (c.charuco) {
    det = detect_charuco(out.image, *c.charuco);
    name = fmt::format("ChArUco {}x{} x {} mm ({})", c.charuco->squares_x, c.charuco->squares_y, c.charuco->square_mm,
                       c.charuco->dictionary);
  } else {
    det = detect_chessboard(out.image, *c.chessboard);
    name = fmt::format("chessboard {}x{} x {} mm", c.chessboard->cols, c.chessboard->rows, c.chessboard->square_mm);
  }
  if (!det.found) {
    out.failure = fmt::format("scale target not found: no {} in the image", name);
    return;
  }
  ScaleChoice& ch = out.choice;
  ch.source = ScaleSource::board;
  ch.reason = "a board on the bed measures the bed plane in this very photo";
  if (c.rectify) {
    const auto rect = rectify_to_plane(out.image, det.img_to_mm, det.px_per_mm);
    out.image = rect.image;
    ch.px_per_mm = rect.px_per_mm;
    for (const auto& p : det.outline) {
      const cv::Vec3d q = rect.img_to_rect * cv::Vec3d(p.x, p.y, 1.0);
      out.outline.emplace_back(static_cast<int>(std::lround(q[0] / q[2])), static_cast<int>(std::lround(q[1] / q[2])));
    }
    ch.name = name + ", rectified";
  } else {
    ch.px_per_mm = det.px_per_mm;
    out.outline = det.outline;
    ch.name = name;
  }
}

void use_camera_plane(ScaledPhoto& out, const CameraProfile& cam, bool rectify) {
  ScaleChoice& ch = out.choice;
  ch.source = ScaleSource::camera_bed_plane;
  ch.reason = "no board in the photo; the camera profile's bed plane was measured for this camera placement";
  if (rectify) {
    const auto rect = rectify_to_plane(out.image, cam.bed_img_to_mm, cam.px_per_mm);
    out.image = rect.image;
    ch.px_per_mm = rect.px_per_mm;
    ch.name = "camera profile bed plane, rectified";
  } else {
    ch.px_per_mm = cam.px_per_mm;
    ch.name = "camera profile bed plane";
  }
}

void note_passed_over(ScaleChoice& ch, const ScaleCandidates& c) {
  const bool plane = c.camera && c.camera->has_bed_plane;
  if (plane && ch.source == ScaleSource::board)
    ch.passed_over.push_back("camera profile bed plane: the board in the photo measures this placement");
  if (c.px_per_mm > 0 && ch.source != ScaleSource::stated)
    ch.passed_over.push_back(fmt::format("stated {} px/mm: {} is measured", c.px_per_mm, ch.name));
  if (c.nominal_width_mm > 0 && ch.source != ScaleSource::none)
    ch.passed_over.push_back(
        fmt::format("nominal width {} mm: it assumes the width the photo is there to measure, and {} is known",
                    c.nominal_width_mm, ch.name));
}

}  // namespace

ScaledPhoto scale_photo(const cv::Mat& photo, const ScaleCandidates& c, const std::string& origin) {
  const bool plane = c.camera && c.camera->has_bed_plane;
  if (c.chessboard && c.charuco) throw InputError("give a chessboard or a ChArUco board, not both");
  if (c.rectify && !c.chessboard && !c.charuco && !plane)
    throw InputError("rectifying needs a chessboard, a ChArUco board or a camera profile with a bed plane");
  ScaledPhoto out;
  out.image = to_gray_float(photo);
  if (c.camera) out.image = undistort_image(out.image, *c.camera, origin);
  if (c.chessboard || c.charuco) {
    find_board(out, c);
  } else if (plane) {
    use_camera_plane(out, *c.camera, c.rectify);
  } else if (c.px_per_mm > 0) {
    out.choice = {ScaleSource::stated,
                  c.px_per_mm,
                  fmt::format("stated {} px/mm", c.px_per_mm),
                  "no board in the photo and no camera bed plane; the scale was stated",
                  {}};
  }
  if (out.choice.source != ScaleSource::none) note_passed_over(out.choice, c);
  return out;
}

}  // namespace tunekit::vision::detail
