#pragma once
// The stages of measure_line_widths (line_width.cpp), private to the vision library:
//   line_detection.cpp     photo -> mask of line pixels (coarse pass: lighting, polarity, threshold)
//   line_centreline.cpp    one mask component -> an ordered, smoothed centreline (and its re-centring)
//   line_edge_profile.cpp  one station of the centreline -> width from an edge-profile fit
// line_width.cpp runs them and flags outlying samples.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "tunekit/fitting/stats.hpp"
#include "tunekit/vision/line_width.hpp"

namespace tunekit::vision::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// MAD -> standard deviation of a normal distribution (1 / Phi^-1(3/4)): robust noise levels.
inline constexpr double kMadToSigma = 1.4826;

/// Bilinear sample of a CV_32F image at (x, y) px, pixel centres at whole numbers; (x, y) must lie
/// inside the image (0 <= x <= cols - 1, 0 <= y <= rows - 1).
inline float bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(std::min(y0 + 1, img.rows - 1));
  const int x1 = std::min(x0 + 1, img.cols - 1);
  return static_cast<float>((1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]));
}

/// Median, NaN when there are no samples (fitting::median gives 0 there).
inline double median_of(std::vector<double> v) { return v.empty() ? kNaN : fitting::median(std::move(v)); }

// ---------------------------------------------------------------- detection

/// The coarse detection pass: a downsampled copy, its contrast against the background and the
/// mask of line pixels.
struct Coarse {
  int f = 1;
  double sx = 1, sy = 1;  // full-resolution px per coarse px
  cv::Mat contrast;       // CV_32F, line positive
  cv::Mat mask;           // CV_8U 0/255
  bool light = false;
  double noise = 0;
};

/// Finds the line pixels; a warning (and an empty mask) when nothing stands out.
Coarse coarse_detect(const cv::Mat& gray, const LineWidthOptions& o, std::vector<std::string>& warnings);

// ---------------------------------------------------------------- centreline

struct Pt {
  double x, y;
};

/// Gaussian smoothing of a sequence (closed: circular; open: renormalized truncated kernel).
template <class T, class Get, class Set>
void smooth_seq(std::vector<T>& v, double sigma, bool closed, Get get, Set set) {
  const auto n = static_cast<long>(v.size());
  // Below 0.3 samples the kernel's neighbour weights are under 0.4 % (exp(-0.5/0.09)): no-op.
  if (n < 3 || sigma <= 0.3) return;
  // The kernel is cut at 3 sigma (99.7 % of its weight).
  const long r = std::min<long>(static_cast<long>(std::ceil(3 * sigma)), closed ? (n - 1) / 2 : n - 1);
  std::vector<double> kern(static_cast<std::size_t>(2 * r + 1));
  for (long i = -r; i <= r; ++i) kern[static_cast<std::size_t>(i + r)] = std::exp(-0.5 * i * i / (sigma * sigma));
  const std::vector<T> src = v;
  for (long i = 0; i < n; ++i) {
    double acc[2] = {0, 0}, wsum = 0;
    for (long k = -r; k <= r; ++k) {
      long j = i + k;
      if (closed) {
        j = ((j % n) + n) % n;
      } else if (j < 0 || j >= n) {
        continue;
      }
      const double kw = kern[static_cast<std::size_t>(k + r)];
      const auto val = get(src[static_cast<std::size_t>(j)]);
      acc[0] += kw * val.first;
      acc[1] += kw * val.second;
      wsum += kw;
    }
    set(v[static_cast<std::size_t>(i)], acc[0] / wsum, acc[1] / wsum);
  }
}

/// A component's centreline in full-resolution px, oriented (open lines from their left, then
/// top, end; loops counterclockwise in the image from their rightmost point), at `step_px`.
struct Centreline {
  std::vector<Pt> points;
  bool closed = false;
  double w0 = 0;     ///< start value of the width (full-resolution px)
  double sigma = 0;  ///< smoothing applied along it (samples); reused for the re-centring
  cv::Rect bbox;     ///< full-resolution px
  bool touches_frame = false;
};

/// The centreline of mask component `label` (stats/labels from connectedComponentsWithStats on
/// c.mask); nullopt when it is no line (too short, a blob, too few skeleton pixels).
std::optional<Centreline> trace_centreline(const Coarse& c, const cv::Mat& labels, const cv::Mat& stats, int label,
                                           const LineWidthOptions& o);

/// Moves the centreline onto the mid-points between the fitted edges of a subset of stations
/// (the skeleton of the coarse mask is off by up to a coarse pixel).
void recentre_centreline(const cv::Mat& gray, bool light, Centreline& cl, double half_window,
                         const LineWidthOptions& o);

// ---------------------------------------------------------------- edge profile

/// A point of the centreline and its unit normal.
struct Station {
  Pt c;
  Pt n;  // unit normal
};

/// Tangents/normals from positions by central differences.
std::vector<Station> stations_from(const std::vector<Pt>& p, bool closed);

/// Half-length (px) of the window across the line for a width start value w0 (px).
double measuring_half_window(double w0);

/// Measures one station: samples the profile across the line (averaged along it) and fits the
/// blurred bar; fills the sample (without s). `prof` is scratch space.
void measure_station(const cv::Mat& img, bool light, const Station& st, double half_window, double along_half,
                     double w_guess, std::vector<double>& prof, WidthSample& out);

/// Measures the stations st[0], st[stride], st[2 stride], ... into out[i] (out is resized to
/// st.size(); the samples between stay default). The stations are independent, so they are
/// measured on OpenCV's worker threads (cv::parallel_for_), each stripe with its own scratch;
/// the samples are the same as one measure_station after another.
void measure_stations(const cv::Mat& img, bool light, const std::vector<Station>& st, std::size_t stride,
                      double half_window, double along_half, double w_guess, std::vector<WidthSample>& out);

}  // namespace tunekit::vision::detail
