#include "tunekit/sim/sim_camera.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

namespace tunekit::sim {
namespace {

constexpr double kSimCamPieceMm = 0.05;    // bead pieces are merged up to this length
constexpr double kSimCamMinSpeed = 0.5;    // mm/s: a (nearly) standing nozzle lays no bead piece
constexpr double kSimCamMaxWidthMm = 3.0;  // a blob, not a line

double sim_cam_segment_distance(double px, double py, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double l2 = dx * dx + dy * dy;
  double t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(px - (ax + t * dx), py - (ay + t * dy));
}

// The lens blur's reach beyond the pixel: 6 sigma (the Gaussian's tail beyond is below 1e-9).
constexpr double kSimCamBlurReach = 6.0;

// The filament's share of a pixel whose centre lies x px inside a straight edge (outside for
// x < 0), the edge blurred by a Gaussian of sigma s px and the light averaged over the pixel's
// width: s [psi((x + 1/2) / s) - psi((x - 1/2) / s)], psi(z) = z Phi(z) + phi(z); s = 0 is the
// sharp edge's clamp(x + 1/2, 0, 1).
double sim_cam_edge(double x, double s) {
  if (!(s > 0)) return std::clamp(x + 0.5, 0.0, 1.0);
  auto psi = [s](double y) {
    const double z = y / s;
    return s * (z * 0.5 * std::erfc(-z * M_SQRT1_2) + std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI));
  };
  return psi(x + 0.5) - psi(x - 0.5);
}

// A bead of half-width `half` px whose centreline lies d px from the pixel's centre.
double sim_cam_bar(double half, double d, double s) {
  return std::max(0.0, sim_cam_edge(half - d, s) + sim_cam_edge(half + d, s) - 1.0);
}

// The joint between two consecutive pieces of one bead: the line through their common point
// that halves the angle between them, given by its unit normal (the mean of the two pieces'
// directions, in image px; image y runs along -Y). Each piece covers the pixels between its two
// joint lines, so the pieces of a curved bead tile it: a piece bounded square to its own
// direction would leave a wedge uncovered on the outside of the curve and cover one twice on the
// inside (the bead's outer half rendered dimmer by d / R, d px from the centreline on a ring of
// R px). `a`, `b`: the two pieces' directions on the bed (mm); `ux`, `uy`: the piece's own
// direction in image px, the normal of a square end, which a turn of 90 deg or more keeps (the
// joint line would run nearly along the pieces).
constexpr double kSimCamMiterMinCos = 0.0;
std::array<double, 2> sim_cam_miter(const std::array<double, 2>& a, const std::array<double, 2>& b, double ux,
                                    double uy) {
  const double la = std::hypot(a[0], a[1]), lb = std::hypot(b[0], b[1]);
  if (!(la > 0) || !(lb > 0) || !(a[0] * b[0] + a[1] * b[1] > kSimCamMiterMinCos * la * lb)) return {ux, uy};
  const double mx = a[0] / la + b[0] / lb, my = -(a[1] / la + b[1] / lb);
  const double m = std::hypot(mx, my);
  return m > 1e-9 ? std::array<double, 2>{mx / m, my / m} : std::array<double, 2>{ux, uy};
}

}  // namespace

void SimPrintBed::deposit(double /*t_s*/, const std::array<double, 4>& pos, double speed, double flow) {
  std::lock_guard<std::mutex> l(mu_);
  const double h = pos[2];
  const bool laying = speed > kSimCamMinSpeed && flow > 0 && h > 0;
  auto close_piece = [&] {
    if (open_ && len_ > 0) {
      const double w = std::min(kSimCamMaxWidthMm, wsum_ / len_);
      if (w > 0.02) pieces_.push_back({ox_, oy_, lx_, ly_, w});
    }
    open_ = false;
  };
  if (!laying) {
    close_piece();
    return;
  }
  if (!open_) {
    open_ = true;
    ox_ = lx_ = pos[0];
    oy_ = ly_ = pos[1];
    wsum_ = len_ = 0;
    return;
  }
  const double step = std::hypot(pos[0] - lx_, pos[1] - ly_);
  const double w = flow / (speed * h);
  wsum_ += w * step;
  len_ += step;
  lx_ = pos[0];
  ly_ = pos[1];
  if (len_ >= kSimCamPieceMm) {
    close_piece();
    open_ = true;
    ox_ = lx_;
    oy_ = ly_;
    wsum_ = len_ = 0;
  }
}

std::size_t SimPrintBed::pieces() const {
  std::lock_guard<std::mutex> l(mu_);
  return pieces_.size();
}

cv::Mat SimPrintBed::photograph(const SimCameraOptions& o, SimCameraFrame* frame_out) const {
  std::vector<Piece> pieces;
  {
    std::lock_guard<std::mutex> l(mu_);
    pieces = pieces_;
  }
  double x0 = 0, x1 = 100, y0 = 0, y1 = 100;
  if (!pieces.empty()) {
    x0 = y0 = 1e300;
    x1 = y1 = -1e300;
    for (const auto& p : pieces) {
      x0 = std::min({x0, p.x0, p.x1});
      x1 = std::max({x1, p.x0, p.x1});
      y0 = std::min({y0, p.y0, p.y1});
      y1 = std::max({y1, p.y0, p.y1});
    }
  }
  x0 -= o.margin_mm;
  y0 -= o.margin_mm;
  x1 += o.margin_mm;
  y1 += o.margin_mm;
  const double ppm = o.px_per_mm;
  const int W = static_cast<int>(std::ceil((x1 - x0) * ppm)), H = static_cast<int>(std::ceil((y1 - y0) * ppm));
  if (frame_out) *frame_out = {x0, y1, ppm, cv::Size(W, H)};

  // Coverage of the filament as a camera pixel records it: the bead blurred by the lens (a
  // Gaussian of sigma blur_px), then integrated over the pixel's area. Blurring after sampling
  // (a pixel grid of sharp coverage, then a discrete blur) is not the same picture: its edges move
  // by up to 0.04 px with where they fall between pixel centres. Each piece covers the stretch of
  // the pixel along the bead between its joint lines (sim_cam_miter; pieces of one continuous bead
  // add up, so the bead's width changes where the flow changed, not a round cap early, and a
  // curved bead is as bright on the outside of the curve as on the inside); the first and the last
  // piece of a bead end in a round cap.
  cv::Mat body(H, W, CV_32F, cv::Scalar(0)), caps(H, W, CV_32F, cv::Scalar(0));
  const double reach = 0.5 + kSimCamBlurReach * o.blur_px;
  auto direction = [](const Piece& q) { return std::array<double, 2>{q.x1 - q.x0, q.y1 - q.y0}; };
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const Piece& p = pieces[i];
    const bool cap0 = i == 0 || pieces[i - 1].x1 != p.x0 || pieces[i - 1].y1 != p.y0;
    const bool cap1 = i + 1 == pieces.size() || pieces[i + 1].x0 != p.x1 || pieces[i + 1].y0 != p.y1;
    const double ax = (p.x0 - x0) * ppm, ay = (y1 - p.y0) * ppm, bx = (p.x1 - x0) * ppm, by = (y1 - p.y1) * ppm;
    const double len = std::hypot(bx - ax, by - ay);
    const double ux = len > 0 ? (bx - ax) / len : 1.0, uy = len > 0 ? (by - ay) / len : 0.0;
    const auto n0 =
        cap0 ? std::array<double, 2>{ux, uy} : sim_cam_miter(direction(pieces[i - 1]), direction(p), ux, uy);
    const auto n1 =
        cap1 ? std::array<double, 2>{ux, uy} : sim_cam_miter(direction(p), direction(pieces[i + 1]), ux, uy);
    const double half = p.width_mm * ppm / 2;
    const int u0 = std::max(0, static_cast<int>(std::floor(std::min(ax, bx) - half - reach)));
    const int u1 = std::min(W - 1, static_cast<int>(std::ceil(std::max(ax, bx) + half + reach)));
    const int v0 = std::max(0, static_cast<int>(std::floor(std::min(ay, by) - half - reach)));
    const int v1 = std::min(H - 1, static_cast<int>(std::ceil(std::max(ay, by) + half + reach)));
    for (int v = v0; v <= v1; ++v) {
      float* brow = body.ptr<float>(v);
      float* crow = caps.ptr<float>(v);
      for (int u = u0; u <= u1; ++u) {
        const double rx = u + 0.5 - ax, ry = v + 0.5 - ay;
        const double t = rx * ux + ry * uy, d = std::abs(ry * ux - rx * uy);
        // The share of the pixel between the piece's two joint lines (along the bead).
        const double s0 = rx * n0[0] + ry * n0[1], s1 = (u + 0.5 - bx) * n1[0] + (v + 0.5 - by) * n1[1];
        const double overlap = std::max(0.0, std::clamp(s0 + 0.5, 0.0, 1.0) + std::clamp(0.5 - s1, 0.0, 1.0) - 1.0);
        if (overlap > 0) brow[u] += static_cast<float>(overlap * sim_cam_bar(half, d, o.blur_px));
        if ((cap0 && t < 0) || (cap1 && t > len)) {
          const double c = sim_cam_bar(half, sim_cam_segment_distance(u + 0.5, v + 0.5, ax, ay, bx, by), o.blur_px);
          if (c > crow[u]) crow[u] = static_cast<float>(c);
        }
      }
    }
  }
  cv::Mat cover = cv::max(cv::min(body, 1.0), caps);

  // The bed: a smooth texture (low-pass noise), then lighting and sensor noise.
  std::seed_seq seeds{o.seed, noise_seed_};
  std::mt19937 rng = noise_seed_ == 0 ? std::mt19937(o.seed) : std::mt19937(seeds);
  std::normal_distribution<float> n01(0.f, 1.f);
  cv::Mat tex(std::max(2, H / 16), std::max(2, W / 16), CV_32F);
  for (int v = 0; v < tex.rows; ++v)
    for (int u = 0; u < tex.cols; ++u) tex.at<float>(v, u) = n01(rng);
  cv::GaussianBlur(tex, tex, cv::Size(0, 0), 1.5);
  cv::resize(tex, tex, cv::Size(W, H), 0, 0, cv::INTER_CUBIC);
  cv::Mat img(H, W, CV_8U);
  const double cx = W / 2.0, cy = H / 2.0, r2max = cx * cx + cy * cy;
  for (int v = 0; v < H; ++v) {
    const float* cv_ = cover.ptr<float>(v);
    const float* tv = tex.ptr<float>(v);
    auto* out = img.ptr<unsigned char>(v);
    for (int u = 0; u < W; ++u) {
      const double bed = o.bed_level + 6.0 * tv[u];
      const double scene = bed * (1 - cv_[u]) + o.filament_level * cv_[u];
      const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / r2max;
      const double light = (1 - o.vignetting * r2) * (1 - o.gradient / 2 + o.gradient * u / W);
      out[u] = cv::saturate_cast<unsigned char>(scene * light + o.noise_sigma * n01(rng));
    }
  }
  return img;
}

}  // namespace tunekit::sim
