#pragma once
// Width profiles of printed lines in an image.
//
// Pipeline: (1) a coarse, downsampled pass flattens the background (on a further-reduced copy:
// a robust polynomial lighting surface, then morphological closing or opening of the rest, so
// vignetting and uneven lighting drop out up to the frame edge), picks the polarity (light or
// dark filament), thresholds and keeps elongated connected components; features far fainter
// than the strongest line (< 30 % of its contrast) are dropped with a warning;
// (2) each component is thinned to a skeleton, the longest path through it becomes the
// centreline (closed loops such as Holtrup's (2019) ring are cut and re-closed), which is smoothed
// and resampled at a fixed arc-length step; (3) at every sample a blurred-bar model
// I(u) = b0 + b1 u + c [E(u; a) - E(u; b)], E(u; a) the step Phi((x - a)/sigma) averaged over the
// pixel's width around u, is fitted by damped Gauss-Newton to the full-resolution pixels within a
// short stretch of the tangent, each at its own offset u across the line (not to values
// interpolated between pixels, which the model does not describe); a and b are the sub-pixel
// edges, b - a the width, sigma the lens's blur. The centreline is then re-centred on the measured
// mid-points and the profile measured again.
//
// Everything here is in pixels of the image passed in; scale (mm) is applied by the caller.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

namespace tunekit::vision {

enum class LinePolarity { automatic, dark, light };

/// Per-sample flags (bit mask).
enum LineFlag : std::uint8_t {
  kFlagOutOfFrame = 1,  ///< the measuring window leaves the image
  kFlagOccluded = 2,    ///< no clean edges here (glare, dirt, gap): width not measured
  kFlagMerged = 4,      ///< a neighbouring line is inside the window or the width jumps
};

struct LineWidthOptions {
  LinePolarity polarity = LinePolarity::automatic;
  double step_px = 1.0;         ///< spacing of profile samples along the centreline (px)
  double along_half_px = 1.0;   ///< half-length of the averaging stretch along the tangent (px)
  double min_length_px = 60.0;  ///< shorter components are not lines (px of centreline)
  int max_lines = 32;
  /// Downsampling of the coarse detection pass; 0 picks it from the image size.
  int coarse_factor = 0;
  /// Nonzero pixels (CV_8U, same size as the image) are ignored by the detection
  /// (e.g. the chessboard of a scale target).
  cv::Mat exclude_mask;
};

struct WidthSample {
  double s_px = 0;             ///< arc length along the centreline from its start (px)
  double x_px = 0, y_px = 0;   ///< centre (mid-point of the edges when measured)
  double nx = 0, ny = 0;       ///< unit normal (edge "a" lies at -width/2 along it)
  double width_px = 0;         ///< NaN when not measured (see flags)
  double confidence = 0;       ///< 0..1, from the edge-position uncertainty of the fit
  double width_stderr_px = 0;  ///< standard error of width_px from the fit
  double contrast = 0;         ///< fitted line/bed contrast (image units, signed away)
  double blur_px = 0;          ///< fitted edge blur sigma (px)
  std::uint8_t flags = 0;
  bool valid() const { return flags == 0 && width_px == width_px; }
};

struct MeasuredLine {
  std::vector<WidthSample> samples;
  bool closed = false;         ///< a loop (ring): the profile wraps around
  bool touches_frame = false;  ///< the segmented line reaches the image border
  cv::Rect bbox;               ///< of the segmented component (px)
  double mean_width_px = 0, std_width_px = 0;
  double median_contrast = 0;
  int valid_samples = 0;
  double length_px = 0;  ///< centreline length (px)
};

struct LineWidthResult {
  int width = 0, height = 0;
  bool light_lines = false;  ///< detected (or requested) polarity
  int coarse_factor = 1;
  double noise_sigma = 0;           ///< robust background noise estimate (image units)
  std::vector<MeasuredLine> lines;  ///< longest first
  std::vector<std::string> warnings;
};

/// Reads an image as single-channel float (grey; colour is converted to luminance; 16-bit
/// stays 16-bit in value). Throws InputError when the file cannot be read or is empty.
cv::Mat load_gray_image(const std::string& path);
/// The same of an image file's bytes already read; `path` locates the errors.
cv::Mat gray_image_from_bytes(std::string_view bytes, const std::string& path);

/// Converts any 1/3/4-channel 8/16/32-bit image to single-channel CV_32F.
cv::Mat to_gray_float(const cv::Mat& image);

/// Finds the printed lines in `gray` (CV_32F) and measures their width profiles.
/// Does not throw for "no line found" (the result is empty); throws InputError for an empty image.
LineWidthResult measure_line_widths(const cv::Mat& gray, const LineWidthOptions& options = {});

/// Fills mean/std/valid_samples of a line from its samples.
void summarize_line(MeasuredLine& line);

}  // namespace tunekit::vision
