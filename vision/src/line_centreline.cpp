// Line centreline: from one component of the detection mask to an ordered, smoothed path along
// the middle of the line (thinning, the longest geodesic path through the skeleton, uniform
// resampling, Gaussian smoothing, orientation), and its re-centring on measured edge mid-points.

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "line_width_stages.hpp"

namespace tunekit::vision::detail {
namespace {

// The component mask gets a border of zeros this wide: thinning needs a zero border and the
// flood fill that finds holes starts in the corner outside the component.
constexpr int kComponentPadPx = 2;
// A hole larger than 60 coarse px and than 8 (half-width)^2 makes a loop (the inside of a ring):
// specks of glare or dust inside a bead are a few pixels; a ring's inside is many line widths
// across. Smaller holes are filled.
constexpr double kLoopHoleMinAreaPx = 60.0;
constexpr double kLoopHoleMinAreaPerHalfWidthSq = 8.0;
// A loop is cut by clearing the skeleton within this many px of its first pixel (a 5 x 5 block),
// so the longest path runs once around it instead of stopping next to where it started.
constexpr int kLoopCutRadiusPx = 2;
// Width start value: twice the median distance transform on the skeleton (the distance to the
// nearest background pixel's centre, which overstates the half-width by up to half a pixel), less
// half a pixel, scaled to full-resolution px; at least 2 px. Only a start value: the edge fit
// measures the width.
constexpr double kWidthFromDistanceOffsetPx = 0.5;
constexpr double kMinWidthStartPx = 2.0;
// An open feature shorter than 2.5 of its own widths is a blob (a drop of filament, dirt), not a
// line with a width profile along it.
constexpr double kMinOpenLengthPerWidth = 2.5;
// Smoothing of the skeleton path, Gaussian sigma: at least 2 coarse px (the skeleton steps in
// coarse pixels), half a width (it wanders within the line's width) and 3 px.
constexpr double kSmoothCoarsePx = 2.0;
constexpr double kSmoothPerWidth = 0.5;
constexpr double kSmoothMinPx = 3.0;
// Open lines lose a width plus 2 coarse px at each end: the ends are round caps where the
// skeleton curls and the width across the path is not the bead's width.
constexpr double kEndTrimCoarsePx = 2.0;
// ... and are dropped when fewer than 3 stations would remain after the trim.
constexpr std::size_t kMinStationsAfterTrim = 3;
// Re-centring measures every 8th station (8 px apart at the default 1 px step): the offsets are
// smoothed over several widths anyway, and it costs an eighth of a full pass.
constexpr std::size_t kRecentreStride = 8;
// Stations whose smoothed weight of measured neighbours is below 1e-3 (further than about 3.7
// smoothing sigmas from any measured station) keep their position.
constexpr double kRecentreMinWeight = 1e-3;

// Zhang-Suen thinning of a 0/1 image with a zero border, in place.
void thin(cv::Mat& m) {
  std::vector<int> fg;
  const int w = m.cols;
  for (int y = 1; y < m.rows - 1; ++y)
    for (int x = 1; x < w - 1; ++x)
      if (m.at<uchar>(y, x)) fg.push_back(y * w + x);
  uchar* d = m.data;
  std::vector<int> del;
  bool changed = true;
  while (changed) {
    changed = false;
    for (int pass = 0; pass < 2; ++pass) {
      del.clear();
      for (int i : fg) {
        if (!d[i]) continue;
        const int p2 = d[i - w], p3 = d[i - w + 1], p4 = d[i + 1], p5 = d[i + w + 1], p6 = d[i + w], p7 = d[i + w - 1],
                  p8 = d[i - 1], p9 = d[i - w - 1];
        const int b = p2 + p3 + p4 + p5 + p6 + p7 + p8 + p9;
        if (b < 2 || b > 6) continue;
        const int a = (!p2 && p3) + (!p3 && p4) + (!p4 && p5) + (!p5 && p6) + (!p6 && p7) + (!p7 && p8) + (!p8 && p9) +
                      (!p9 && p2);
        if (a != 1) continue;
        if (pass == 0 ? (p2 * p4 * p6 == 0 && p4 * p6 * p8 == 0) : (p2 * p4 * p8 == 0 && p2 * p6 * p8 == 0))
          del.push_back(i);
      }
      for (int i : del) d[i] = 0;
      if (!del.empty()) changed = true;
    }
    fg.erase(std::remove_if(fg.begin(), fg.end(), [&](int i) { return !d[i]; }), fg.end());
  }
}

// Longest geodesic path through the skeleton pixels of `m` (0/1), as pixel indices.
std::vector<int> longest_path(const cv::Mat& m) {
  const int w = m.cols;
  std::vector<int> nodes;
  for (int y = 1; y < m.rows - 1; ++y)
    for (int x = 1; x < w - 1; ++x)
      if (m.at<uchar>(y, x)) nodes.push_back(y * w + x);
  if (nodes.empty()) return {};
  std::vector<double> dist(m.total());
  std::vector<int> prev(m.total());
  const int off[8] = {-w - 1, -w, -w + 1, -1, 1, w - 1, w, w + 1};
  const double wt[8] = {M_SQRT2, 1, M_SQRT2, 1, 1, M_SQRT2, 1, M_SQRT2};
  const uchar* d = m.data;
  auto dijkstra = [&](int src) {
    for (int i : nodes) dist[static_cast<std::size_t>(i)] = std::numeric_limits<double>::infinity();
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
    dist[static_cast<std::size_t>(src)] = 0;
    prev[static_cast<std::size_t>(src)] = -1;
    q.push({0, src});
    int far = src;
    while (!q.empty()) {
      const auto [dd, i] = q.top();
      q.pop();
      if (dd > dist[static_cast<std::size_t>(i)]) continue;
      if (dd > dist[static_cast<std::size_t>(far)]) far = i;
      for (int k = 0; k < 8; ++k) {
        const int j = i + off[k];
        if (!d[j]) continue;
        const double nd = dd + wt[k];
        if (nd < dist[static_cast<std::size_t>(j)]) {
          dist[static_cast<std::size_t>(j)] = nd;
          prev[static_cast<std::size_t>(j)] = i;
          q.push({nd, j});
        }
      }
    }
    return far;
  };
  const int a = dijkstra(nodes.front());
  const int b = dijkstra(a);
  std::vector<int> path;
  for (int i = b; i != -1; i = prev[static_cast<std::size_t>(i)]) path.push_back(i);
  return path;
}

// Resamples a polyline at uniform spacing `step` (closed: wraps).
std::vector<Pt> resample(const std::vector<Pt>& p, double step, bool closed) {
  std::vector<Pt> q = p;
  if (closed) q.push_back(p.front());
  std::vector<double> s(q.size(), 0.0);
  for (std::size_t i = 1; i < q.size(); ++i) s[i] = s[i - 1] + std::hypot(q[i].x - q[i - 1].x, q[i].y - q[i - 1].y);
  const double total = s.back();
  std::vector<Pt> out;
  if (total <= 0) return out;
  const auto n = static_cast<std::size_t>(std::floor(total / step)) + (closed ? 0 : 1);
  std::size_t j = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double sk = static_cast<double>(k) * step;
    while (j + 1 < q.size() - 1 && s[j + 1] < sk) ++j;
    const double seg = s[j + 1] - s[j];
    const double t = seg > 0 ? std::clamp((sk - s[j]) / seg, 0.0, 1.0) : 0.0;
    out.push_back({q[j].x + t * (q[j + 1].x - q[j].x), q[j].y + t * (q[j + 1].y - q[j].y)});
  }
  return out;
}

void smooth_points(std::vector<Pt>& p, double sigma_samples, bool closed) {
  smooth_seq(
      p, sigma_samples, closed, [](const Pt& q) { return std::make_pair(q.x, q.y); },
      [](Pt& q, double a, double b) {
        q.x = a;
        q.y = b;
      });
}

}  // namespace

std::optional<Centreline> trace_centreline(const Coarse& c, const cv::Mat& labels, const cv::Mat& stats, int lab,
                                           const LineWidthOptions& o) {
  const double scale = 0.5 * (c.sx + c.sy);
  const int bx = stats.at<int>(lab, cv::CC_STAT_LEFT), by = stats.at<int>(lab, cv::CC_STAT_TOP);
  const int bw = stats.at<int>(lab, cv::CC_STAT_WIDTH), bh = stats.at<int>(lab, cv::CC_STAT_HEIGHT);
  const int pad = kComponentPadPx;
  cv::Mat m = cv::Mat::zeros(bh + 2 * pad, bw + 2 * pad, CV_8U);
  {
    cv::Mat roi = m(cv::Rect(pad, pad, bw, bh));
    cv::Mat sel = labels(cv::Rect(bx, by, bw, bh)) == lab;
    roi.setTo(1, sel);
  }
  // Holes: large ones make a loop, small ones (specks) are filled.
  cv::Mat outside = m.clone();
  cv::floodFill(outside, cv::Point(0, 0), 2);
  cv::Mat hole_mask = outside == 0;
  cv::Mat hl, hs, hc;
  const int nh = cv::connectedComponentsWithStats(hole_mask, hl, hs, hc, 4, CV_32S);
  cv::Mat dt;
  cv::distanceTransform(m, dt, cv::DIST_L2, 3);
  double dmax = 0;
  cv::minMaxLoc(dt, nullptr, &dmax);
  bool closed = false;
  for (int h = 1; h < nh; ++h) {
    if (hs.at<int>(h, cv::CC_STAT_AREA) > std::max(kLoopHoleMinAreaPx, kLoopHoleMinAreaPerHalfWidthSq * dmax * dmax))
      closed = true;
    else m.setTo(1, hl == h);
  }
  cv::Mat sk = m.clone();
  thin(sk);
  std::vector<double> dts;
  for (int y = 0; y < sk.rows; ++y)
    for (int x = 0; x < sk.cols; ++x)
      if (sk.at<uchar>(y, x)) dts.push_back(dt.at<float>(y, x));
  if (dts.size() < 3) return std::nullopt;
  const double w0 =
      std::max(kMinWidthStartPx, (2.0 * median_of(dts) - kWidthFromDistanceOffsetPx) * scale);  // full-res px

  if (closed) {
    // Cut the loop next to its first pixel so the longest path runs once around it.
    int cy = -1, cx = -1;
    for (int y = 0; y < sk.rows && cy < 0; ++y)
      for (int x = 0; x < sk.cols; ++x)
        if (sk.at<uchar>(y, x)) {
          cy = y;
          cx = x;
          break;
        }
    for (int y = std::max(0, cy - kLoopCutRadiusPx); y <= std::min(sk.rows - 1, cy + kLoopCutRadiusPx); ++y)
      for (int x = std::max(0, cx - kLoopCutRadiusPx); x <= std::min(sk.cols - 1, cx + kLoopCutRadiusPx); ++x)
        sk.at<uchar>(y, x) = 0;
  }
  const std::vector<int> path = longest_path(sk);
  if (path.size() < 3) return std::nullopt;
  std::vector<Pt> pts;
  pts.reserve(path.size());
  for (int i : path) {
    const int y = i / sk.cols - pad + by, x = i % sk.cols - pad + bx;
    pts.push_back({(x + 0.5) * c.sx - 0.5, (y + 0.5) * c.sy - 0.5});
  }
  double len = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) len += std::hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y);
  if (len < o.min_length_px) return std::nullopt;
  if (!closed && len < kMinOpenLengthPerWidth * w0) return std::nullopt;  // a blob, not a line

  Centreline cl;
  cl.closed = closed;
  cl.w0 = w0;
  cl.bbox = cv::Rect(static_cast<int>(bx * c.sx), static_cast<int>(by * c.sy), static_cast<int>(bw * c.sx),
                     static_cast<int>(bh * c.sy));
  cl.touches_frame = bx <= 0 || by <= 0 || bx + bw >= c.mask.cols || by + bh >= c.mask.rows;

  const double step = o.step_px > 0 ? o.step_px : 1.0;
  std::vector<Pt> q = resample(pts, step, closed);
  cl.sigma = std::max({kSmoothCoarsePx * scale, kSmoothPerWidth * w0, kSmoothMinPx}) / step;
  smooth_points(q, cl.sigma, closed);
  if (!closed) {
    const auto trim = static_cast<std::size_t>(std::ceil((w0 + kEndTrimCoarsePx * scale) / step));
    if (q.size() <= 2 * trim + kMinStationsAfterTrim) return std::nullopt;
    q = std::vector<Pt>(q.begin() + static_cast<std::ptrdiff_t>(trim), q.end() - static_cast<std::ptrdiff_t>(trim));
  }
  // Orientation: open lines start at their left (then top) end; loops run counterclockwise as
  // seen in the image and start at their rightmost point.
  if (closed) {
    double area = 0;
    for (std::size_t i = 0; i < q.size(); ++i) {
      const Pt& a = q[i];
      const Pt& b = q[(i + 1) % q.size()];
      area += a.x * b.y - b.x * a.y;
    }
    if (area > 0) std::reverse(q.begin(), q.end());
    const auto it = std::max_element(q.begin(), q.end(), [](const Pt& a, const Pt& b) { return a.x < b.x; });
    std::rotate(q.begin(), it, q.end());
  } else if (q.front().x > q.back().x || (q.front().x == q.back().x && q.front().y > q.back().y)) {
    std::reverse(q.begin(), q.end());
  }
  cl.points = std::move(q);
  return cl;
}

void recentre_centreline(const cv::Mat& gray, bool light, Centreline& cl, double half_window,
                         const LineWidthOptions& o) {
  std::vector<Pt>& q = cl.points;
  const bool closed = cl.closed;
  std::vector<Station> st = stations_from(q, closed);
  std::vector<std::pair<double, double>> off(q.size(), {0.0, 0.0});
  std::vector<double> known(q.size(), 0.0);
  std::vector<WidthSample> ws;
  measure_stations(gray, light, st, kRecentreStride, half_window, o.along_half_px, cl.w0, ws);
  for (std::size_t i = 0; i < st.size(); i += kRecentreStride) {
    if (ws[i].flags == 0 && std::isfinite(ws[i].width_px)) {
      off[i] = {ws[i].x_px - st[i].c.x, ws[i].y_px - st[i].c.y};
      known[i] = 1;
    }
  }
  // Weighted Gaussian smoothing of the offsets (unknown stations get weight 0).
  std::vector<std::pair<double, double>> wo(q.size());
  std::vector<std::pair<double, double>> wk(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    wo[i] = {off[i].first * known[i], off[i].second * known[i]};
    wk[i] = {known[i], 0.0};
  }
  auto get = [](const std::pair<double, double>& v) { return v; };
  auto set = [](std::pair<double, double>& v, double a, double b) { v = {a, b}; };
  smooth_seq(wo, cl.sigma, closed, get, set);
  smooth_seq(wk, cl.sigma, closed, get, set);
  for (std::size_t i = 0; i < q.size(); ++i)
    if (wk[i].first > kRecentreMinWeight) {
      q[i].x += wo[i].first / wk[i].first;
      q[i].y += wo[i].second / wk[i].first;
    }
}

}  // namespace tunekit::vision::detail
