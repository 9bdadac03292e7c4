#pragma once
// Synthetic photos of printed lines with known truth, for the line-width tests and benchmarks.
//
// Shapes are described by a signed distance sd(x, y) in pixels (negative inside). A pixel
// (which covers [x-0.5, x+0.5] x [y-0.5, y+0.5]) whose centre is farther than `margin` from
// the boundary is fully in or out; the others are supersampled (ss x ss points) and
// area-averaged, which is exact anti-aliasing up to the supersampling. The photo is then
// bed + (line - bed) * coverage, blurred with a Gaussian PSF, multiplied by a radial
// vignetting falloff and a left-to-right lighting gradient, given Gaussian noise and quantized
// to 8 bits.

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace tunekit::test::render {

using Sdf = std::function<double(double x, double y)>;

/// Coverage in [0, 1] (CV_32F) of the shape sd < 0.
inline cv::Mat coverage(int w, int h, const Sdf& sd, int ss = 16, double margin = 1.0) {
  cv::Mat cov(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    float* row = cov.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      const double d = sd(x, y);
      if (d > margin) {
        row[x] = 0.f;
      } else if (d < -margin) {
        row[x] = 1.f;
      } else {
        int in = 0;
        for (int j = 0; j < ss; ++j)
          for (int i = 0; i < ss; ++i)
            if (sd(x - 0.5 + (i + 0.5) / ss, y - 0.5 + (j + 0.5) / ss) < 0) ++in;
        row[x] = static_cast<float>(in) / static_cast<float>(ss * ss);
      }
    }
  }
  return cov;
}

/// Distance from (x, y) to the segment p-q.
inline double seg_dist(double x, double y, double px, double py, double qx, double qy) {
  const double vx = qx - px, vy = qy - py;
  const double l2 = vx * vx + vy * vy;
  const double t = l2 > 0 ? std::clamp(((x - px) * vx + (y - py) * vy) / l2, 0.0, 1.0) : 0.0;
  return std::hypot(x - px - t * vx, y - py - t * vy);
}

/// A straight line of width w (px) with square ends, from (x0, y0) to (x1, y1) (centreline).
inline Sdf straight_line(double x0, double y0, double x1, double y1, double w) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const double tx = (x1 - x0) / len, ty = (y1 - y0) / len;
  return [=](double x, double y) {
    const double u = (x - x0) * tx + (y - y0) * ty;   // along
    const double v = -(x - x0) * ty + (y - y0) * tx;  // across
    const double du = std::abs(u - 0.5 * len) - 0.5 * len;
    const double dv = std::abs(v) - 0.5 * w;
    return std::max(du, dv);
  };
}

/// A polyline of width w (px) with round joins and ends.
inline Sdf polyline(std::vector<cv::Point2d> pts, double w) {
  return [pts = std::move(pts), w](double x, double y) {
    double d = 1e300;
    for (std::size_t i = 1; i < pts.size(); ++i)
      d = std::min(d, seg_dist(x, y, pts[i - 1].x, pts[i - 1].y, pts[i].x, pts[i].y));
    return d - 0.5 * w;
  };
}

/// A ring of centre (cx, cy) and radius r (px) whose width (px) depends on the angle
/// phi = atan2(-(y - cy), x - cx) (counterclockwise as seen in the image, 0 = to the right).
inline Sdf ring(double cx, double cy, double r, std::function<double(double phi)> width) {
  return [=](double x, double y) {
    const double dx = x - cx, dy = y - cy;
    const double phi = std::atan2(-dy, dx);
    return std::abs(std::hypot(dx, dy) - r) - 0.5 * width(phi);
  };
}

/// Union of shapes.
inline Sdf unite(std::vector<Sdf> parts) {
  return [parts = std::move(parts)](double x, double y) {
    double d = 1e300;
    for (const auto& p : parts) d = std::min(d, p(x, y));
    return d;
  };
}

/// Dark squares of a chessboard with `cols` x `rows` squares of `sq` px, top-left corner at
/// (x0, y0); its (cols-1) x (rows-1) inner corners are at x0 + i sq, y0 + j sq.
inline Sdf chessboard(double x0, double y0, int cols, int rows, double sq) {
  return [=](double x, double y) {
    const double u = (x - x0) / sq, v = (y - y0) / sq;
    if (u < 0 || v < 0 || u >= cols || v >= rows) {
      const double dx = std::max({-u, u - cols, 0.0}) * sq, dy = std::max({-v, v - rows, 0.0}) * sq;
      return std::max(std::hypot(dx, dy), 1e-9);
    }
    const int iu = static_cast<int>(std::floor(u)), iv = static_cast<int>(std::floor(v));
    const double du = std::min(u - iu, iu + 1 - u) * sq, dv = std::min(v - iv, iv + 1 - v) * sq;
    const double d = std::min(du, dv);
    return ((iu + iv) % 2 == 0) ? -d : d;  // dark squares where iu + iv is even
  };
}

/// Maps a shape through a homography: the image point (x, y) shows the shape at Hinv (x, y).
/// `scale` (shape units per image px, the smallest over the image) keeps distances in image px.
inline Sdf warped(Sdf sd, cv::Matx33d Hinv, double scale) {
  return [=](double x, double y) {
    const cv::Vec3d p = Hinv * cv::Vec3d(x, y, 1.0);
    return sd(p[0] / p[2], p[1] / p[2]) / scale;
  };
}

struct Photo {
  double bed = 200;         ///< bed brightness (grey levels)
  double line = 60;         ///< line brightness
  double blur_px = 1.0;     ///< Gaussian PSF sigma (px); 0 = none
  double vignetting = 0.0;  ///< relative falloff at the image corners
  double gradient = 0.0;    ///< uneven lighting: relative brightness change from the left to the right edge
  double noise = 0.0;       ///< Gaussian noise sigma (grey levels)
  unsigned seed = 1;
};

/// The photo (CV_8U) of a coverage map.
inline cv::Mat photograph(const cv::Mat& cov, const Photo& p) {
  cv::Mat img = p.bed + (p.line - p.bed) * cov;
  if (p.blur_px > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), p.blur_px, p.blur_px, cv::BORDER_REPLICATE);
  if (p.vignetting > 0) {
    const double cx = 0.5 * (img.cols - 1), cy = 0.5 * (img.rows - 1), r2max = cx * cx + cy * cy;
    for (int y = 0; y < img.rows; ++y) {
      float* row = img.ptr<float>(y);
      for (int x = 0; x < img.cols; ++x) {
        const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
        row[x] = static_cast<float>(row[x] * (1.0 - p.vignetting * r2));
      }
    }
  }
  if (p.gradient != 0) {
    for (int y = 0; y < img.rows; ++y) {
      float* row = img.ptr<float>(y);
      for (int x = 0; x < img.cols; ++x)
        row[x] = static_cast<float>(row[x] * (1.0 + p.gradient * (x / std::max(1.0, img.cols - 1.0) - 0.5)));
    }
  }
  if (p.noise > 0) {
    cv::Mat n(img.size(), CV_32F);
    cv::RNG rng(p.seed);
    rng.fill(n, cv::RNG::NORMAL, 0.0, p.noise);
    img += n;
  }
  cv::Mat out;
  img.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

}  // namespace tunekit::test::render
