#include "tunekit/vision/line_width.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "tunekit/fitting/error.hpp"
#include "tunekit/vision/image_io.hpp"
#include "tunekit/fitting/stats.hpp"

namespace tunekit::vision {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Lines with a median contrast below this fraction of the strongest line's are not lines.
constexpr double kFaintFraction = 0.3;

// Median, NaN when there are no samples (fitting::median gives 0 there).
double median_of(std::vector<double> v) { return v.empty() ? kNaN : fitting::median(std::move(v)); }

// ---------------------------------------------------------------- coarse detection

struct Coarse {
  int f = 1;
  double sx = 1, sy = 1;  // full-resolution px per coarse px
  cv::Mat contrast;       // CV_32F, line positive
  cv::Mat mask;           // CV_8U 0/255
  bool light = false;
  double noise = 0;
};

int pick_coarse_factor(int w, int h) {
  const double px = static_cast<double>(w) * h;
  return std::max(1, static_cast<int>(std::ceil(std::sqrt(px / 1.2e6))));
}

// Robust polynomial surface (total degree up to 4) through a small CV_32F image: iteratively
// reweighted least squares that drops pixels more than 2.5 robust sigmas from the surface
// (the printed lines, dirt), so it describes the bed's lighting only. Nonzero pixels of
// `exclude` (CV_8U, same size, may be empty) are not used (a scale target).
cv::Mat fit_lighting(const cv::Mat& img, const cv::Mat& exclude) {
  const int W = img.cols, H = img.rows;
  const int degree = std::min(W, H) >= 24 ? 4 : (std::min(W, H) >= 8 ? 2 : 0);  // >= 36 samples per term
  std::vector<std::pair<int, int>> terms;
  for (int d = 0; d <= degree; ++d)
    for (int i = 0; i <= d; ++i) terms.emplace_back(d - i, i);
  const auto nt = static_cast<Eigen::Index>(terms.size());
  auto coord = [](int v, int n) { return n > 1 ? 2.0 * v / (n - 1) - 1.0 : 0.0; };
  auto basis = [&](double u, double v, double* out) {
    const double pu[5] = {1, u, u * u, u * u * u, u * u * u * u}, pv[5] = {1, v, v * v, v * v * v, v * v * v * v};
    for (std::size_t t = 0; t < terms.size(); ++t) out[t] = pu[terms[t].first] * pv[terms[t].second];
  };
  // About 3000 samples are plenty for 15 coefficients and keep this to a millisecond or two.
  const int step = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(W) * H / 3000.0))));
  std::vector<std::pair<int, int>> at;
  for (int y = step / 2; y < H; y += step)
    for (int x = step / 2; x < W; x += step)
      if (exclude.empty() || exclude.at<uchar>(y, x) == 0) at.emplace_back(x, y);
  if (at.size() < 3 * terms.size()) return cv::Mat(H, W, CV_32F, cv::Scalar(cv::mean(img)[0]));
  const auto n = static_cast<Eigen::Index>(at.size());
  Eigen::MatrixXd A(n, nt);
  Eigen::VectorXd vals(n);
  {
    std::vector<double> r(terms.size());
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto [x, y] = at[static_cast<std::size_t>(i)];
      basis(coord(x, W), coord(y, H), r.data());
      for (Eigen::Index t = 0; t < nt; ++t) A(i, t) = r[static_cast<std::size_t>(t)];
      vals(i) = img.at<float>(y, x);
    }
  }
  Eigen::VectorXd wt = Eigen::VectorXd::Ones(n);
  Eigen::VectorXd coef = Eigen::VectorXd::Zero(nt);
  for (int it = 0; it < 6; ++it) {
    const Eigen::MatrixXd AtA = A.transpose() * wt.asDiagonal() * A;
    const Eigen::VectorXd Atb = A.transpose() * wt.cwiseProduct(vals);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(AtA);
    if (ldlt.info() != Eigen::Success) break;
    coef = ldlt.solve(Atb);
    const Eigen::VectorXd res = vals - A * coef;
    std::vector<double> kept;
    for (Eigen::Index i = 0; i < n; ++i)
      if (wt(i) != 0) kept.push_back(std::abs(res(i)));
    const double sigma = std::max(1e-6, 1.4826 * median_of(kept));
    for (Eigen::Index i = 0; i < n; ++i) wt(i) = std::abs(res(i)) <= 2.5 * sigma ? 1.0 : 0.0;
  }
  cv::Mat out(H, W, CV_32F);
  std::vector<double> b(terms.size());
  for (int y = 0; y < H; ++y) {
    float* row = out.ptr<float>(y);
    for (int x = 0; x < W; ++x) {
      basis(coord(x, W), coord(y, H), b.data());
      double v = 0;
      for (std::size_t t = 0; t < terms.size(); ++t) v += b[t] * coef(static_cast<Eigen::Index>(t));
      row[x] = static_cast<float>(v);
    }
  }
  return out;
}

Coarse coarse_detect(const cv::Mat& gray, const LineWidthOptions& o, std::vector<std::string>& warnings) {
  Coarse c;
  c.f = o.coarse_factor > 0 ? o.coarse_factor : pick_coarse_factor(gray.cols, gray.rows);
  cv::Mat coarse;
  if (c.f > 1)
    cv::resize(gray, coarse, cv::Size(std::max(1, gray.cols / c.f), std::max(1, gray.rows / c.f)), 0, 0, cv::INTER_AREA);
  else
    coarse = gray;
  c.sx = static_cast<double>(gray.cols) / coarse.cols;
  c.sy = static_cast<double>(gray.rows) / coarse.rows;

  // Background on a further-reduced copy, in two stages. (a) A smooth lighting surface: a
  // low-order polynomial fitted robustly (lines and specks are outliers), which follows
  // vignetting and a lamp at one side right up to the image border, where morphology alone
  // is biased (its window runs out of the image and it mistakes the darkening corners for
  // features). (b) Morphology on what remains: closing removes dark features, opening light
  // ones, so local lighting the polynomial cannot follow (glare, bed texture) drops out too.
  const int g = std::clamp(std::min(coarse.cols, coarse.rows) / 48, 1, 4);
  cv::Mat tiny;
  if (g > 1)
    cv::resize(coarse, tiny, cv::Size(std::max(1, coarse.cols / g), std::max(1, coarse.rows / g)), 0, 0, cv::INTER_AREA);
  else
    tiny = coarse;
  // A scale target in the scene (half dark squares) is neither bed nor line: keep it out of the
  // lighting fit and the polarity vote.
  cv::Mat tiny_ex;
  if (!o.exclude_mask.empty()) {
    cv::resize(o.exclude_mask, tiny_ex, tiny.size(), 0, 0, cv::INTER_AREA);
    tiny_ex = tiny_ex > 0;
  }
  const cv::Mat lighting = fit_lighting(tiny, tiny_ex);
  cv::Mat resid = tiny - lighting;
  if (!tiny_ex.empty()) resid.setTo(0, tiny_ex);
  int k = std::min(21, std::max(3, (std::min(tiny.cols, tiny.rows) / 2) | 1));
  if (k % 2 == 0) ++k;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k));
  cv::Mat closed, opened;
  cv::morphologyEx(resid, closed, cv::MORPH_CLOSE, kernel, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::morphologyEx(resid, opened, cv::MORPH_OPEN, kernel, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  if (o.polarity == LinePolarity::automatic) {
    // Which tail of the residual from the lighting surface is heavier: printed lines are the
    // outliers. (Comparing the closing and opening residues instead mistakes the bed between
    // two close dark lines for a light line.)
    std::vector<double> absr;
    absr.reserve(resid.total() / 4 + 1);
    for (int y = 0; y < resid.rows; y += 2) {
      const float* row = resid.ptr<float>(y);
      for (int x = 0; x < resid.cols; x += 2) absr.push_back(std::abs(row[x]));
    }
    const double cut = 4.0 * 1.4826 * median_of(absr);
    double dark_score = 0, light_score = 0;
    for (int y = 0; y < resid.rows; ++y) {
      const float* row = resid.ptr<float>(y);
      for (int x = 0; x < resid.cols; ++x) {
        if (row[x] > cut) light_score += row[x] - cut;
        if (row[x] < -cut) dark_score += -row[x] - cut;
      }
    }
    c.light = light_score > dark_score;
  } else {
    c.light = o.polarity == LinePolarity::light;
  }
  cv::Mat bg_tiny = c.light ? opened : closed;
  cv::GaussianBlur(bg_tiny, bg_tiny, cv::Size(0, 0), std::max(1.0, k / 4.0), 0, cv::BORDER_REPLICATE);
  bg_tiny += lighting;
  cv::Mat bg;
  cv::resize(bg_tiny, bg, coarse.size(), 0, 0, cv::INTER_LINEAR);
  c.contrast = c.light ? cv::Mat(coarse - bg) : cv::Mat(bg - coarse);

  // Robust noise (MAD) on a subsample, then Otsu on the positive contrast.
  std::vector<double> sub;
  sub.reserve(static_cast<std::size_t>(c.contrast.total() / 3 + 1));
  for (int y = 0; y < c.contrast.rows; y += 3) {
    const float* row = c.contrast.ptr<float>(y);
    for (int x = 0; x < c.contrast.cols; x += 3) sub.push_back(row[x]);
  }
  const double med = median_of(sub);
  for (auto& v : sub) v = std::abs(v - med);
  c.noise = 1.4826 * median_of(sub);
  double maxc = 0;
  cv::minMaxLoc(c.contrast, nullptr, &maxc);
  c.mask = cv::Mat::zeros(coarse.size(), CV_8U);
  if (!(maxc > 0) || maxc < 8.0 * c.noise) {
    warnings.push_back(fmt::format("no feature stands out of the background (largest contrast {:.3g}, noise {:.3g})",
                                   maxc, c.noise));
    return c;
  }
  cv::Mat c8;
  c.contrast.convertTo(c8, CV_8U, 255.0 / maxc);
  const double t8 = cv::threshold(c8, c8, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
  const double thr = std::max(t8 * maxc / 255.0, 5.0 * c.noise);
  c.mask = c.contrast > thr;
  if (!o.exclude_mask.empty()) {
    cv::Mat ex;
    cv::resize(o.exclude_mask, ex, coarse.size(), 0, 0, cv::INTER_NEAREST);
    c.mask.setTo(0, ex);
  }
  return c;
}

// ---------------------------------------------------------------- skeleton and path

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

struct Pt {
  double x, y;
};

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

// Gaussian smoothing of a sequence (closed: circular; open: renormalized truncated kernel).
template <class T, class Get, class Set>
void smooth_seq(std::vector<T>& v, double sigma, bool closed, Get get, Set set) {
  const auto n = static_cast<long>(v.size());
  if (n < 3 || sigma <= 0.3) return;
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

void smooth_points(std::vector<Pt>& p, double sigma_samples, bool closed) {
  smooth_seq(
      p, sigma_samples, closed, [](const Pt& q) { return std::make_pair(q.x, q.y); },
      [](Pt& q, double a, double b) {
        q.x = a;
        q.y = b;
      });
}

// ---------------------------------------------------------------- edge fit

// Standard normal cdf Phi(z) and pdf phi(z) with one exponential: Abramowitz & Stegun 7.1.26
// for erf (absolute error < 1.5e-7, far below image noise), sharing exp(-z^2/2) with the pdf.
inline void normal_cdf_pdf(double z, double& cdf, double& pdf) {
  const double e = std::exp(-0.5 * z * z);
  pdf = 0.3989422804014327 * e;
  const double x = std::abs(z) * M_SQRT1_2;
  const double t = 1.0 / (1.0 + 0.3275911 * x);
  const double poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
  const double erf_abs = 1.0 - poly * e;
  cdf = z >= 0 ? 0.5 * (1.0 + erf_abs) : 0.5 * (1.0 - erf_abs);
}

struct BarFit {
  bool ok = false;
  double b0 = 0, b1 = 0, c = 0, a = 0, b = 0, s = 1;
  double var_w = kNaN;
  bool neighbour = false;
};

// Fits I(u) = b0 + b1 u + c [Phi((u-a)/s) - Phi((u-b)/s)] to p[k] at u = u0 + k.
BarFit fit_bar(const std::vector<double>& p, double u0, double w_guess) {
  BarFit f;
  const int n = static_cast<int>(p.size());
  if (n < 10) return f;
  const int e = 3;
  double ml = 0, mr = 0;
  for (int k = 0; k < e; ++k) {
    ml += p[static_cast<std::size_t>(k)];
    mr += p[static_cast<std::size_t>(n - 1 - k)];
  }
  ml /= e;
  mr /= e;
  const double ul = u0 + (e - 1) / 2.0, ur = u0 + n - 1 - (e - 1) / 2.0;
  double th[6];
  th[1] = (mr - ml) / (ur - ul);
  th[0] = ml - th[1] * ul;
  // Peak in the central region.
  const int half = std::max(1, static_cast<int>(0.5 * w_guess));
  const int mid = static_cast<int>(std::lround(-u0));
  int kp = std::clamp(mid, 0, n - 1);
  for (int k = std::max(0, mid - half); k <= std::min(n - 1, mid + half); ++k)
    if (p[static_cast<std::size_t>(k)] - (th[0] + th[1] * (u0 + k)) >
        p[static_cast<std::size_t>(kp)] - (th[0] + th[1] * (u0 + kp)))
      kp = k;
  auto base = [&](int k) { return th[0] + th[1] * (u0 + k); };
  const double c0 = p[static_cast<std::size_t>(kp)] - base(kp);
  if (!(c0 > 0)) return f;
  auto above = [&](int k) { return p[static_cast<std::size_t>(k)] - base(k) > 0.5 * c0; };
  int kl = kp;
  while (kl > 0 && above(kl - 1)) --kl;
  int kr = kp;
  while (kr < n - 1 && above(kr + 1)) ++kr;
  if (kl == 0 || kr == n - 1) return f;
  auto cross = [&](int k_in, int k_out) {
    const double vi = p[static_cast<std::size_t>(k_in)] - base(k_in) - 0.5 * c0;
    const double vo = p[static_cast<std::size_t>(k_out)] - base(k_out) - 0.5 * c0;
    const double t = vi / (vi - vo);
    return u0 + k_in + t * (k_out - k_in);
  };
  th[2] = c0;
  th[3] = cross(kl, kl - 1);
  th[4] = cross(kr, kr + 1);
  th[5] = std::clamp(0.25 * (th[4] - th[3]) * 0.2, 0.4, 2.0);

  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  auto eval = [&](const double* t, Mat6* JtJ, Vec6* Jtr) {
    double rss = 0;
    if (JtJ) {
      JtJ->setZero();
      Jtr->setZero();
    }
    const double inv_s = 1.0 / t[5];
    for (int k = 0; k < n; ++k) {
      const double u = u0 + k;
      const double za = (u - t[3]) * inv_s, zb = (u - t[4]) * inv_s;
      const bool ea = std::abs(za) <= 6, eb = std::abs(zb) <= 6;
      double Pa = za > 0 ? 1.0 : 0.0, Pb = zb > 0 ? 1.0 : 0.0, fa = 0.0, fb = 0.0;
      if (ea) normal_cdf_pdf(za, Pa, fa);
      if (eb) normal_cdf_pdf(zb, Pb, fb);
      const double r = t[0] + t[1] * u + t[2] * (Pa - Pb) - p[static_cast<std::size_t>(k)];
      rss += r * r;
      if (JtJ) {
        const double j[6] = {1.0, u, Pa - Pb, -t[2] * fa * inv_s, t[2] * fb * inv_s, t[2] * (-fa * za + fb * zb) * inv_s};
        const int m = (ea || eb) ? 6 : 3;  // far from both edges only the background and contrast terms move
        for (int a = 0; a < m; ++a) {
          (*Jtr)(a) += j[a] * r;
          for (int b = 0; b <= a; ++b) (*JtJ)(a, b) += j[a] * j[b];
        }
      }
    }
    if (JtJ)
      for (int a = 0; a < 6; ++a)
        for (int b = a + 1; b < 6; ++b) (*JtJ)(a, b) = (*JtJ)(b, a);
    return rss;
  };
  Mat6 JtJ, JtJ_t;
  Vec6 Jtr, Jtr_t;
  double cost = eval(th, &JtJ, &Jtr);
  double lambda = 1e-3;
  bool converged = false;
  for (int it = 0; it < 40 && !converged; ++it) {
    Mat6 A = JtJ;
    for (int i = 0; i < 6; ++i) A(i, i) *= 1.0 + lambda;
    const Vec6 step = A.ldlt().solve(-Jtr);
    double trial[6];
    for (int i = 0; i < 6; ++i) trial[i] = th[i] + step(i);
    const bool in_domain = trial[5] > 0.1 && trial[4] - trial[3] > 1.0 && trial[2] > 0 &&
                           trial[3] > u0 && trial[4] < u0 + n - 1 && trial[5] < 0.5 * (trial[4] - trial[3]) + 2.0;
    const double new_cost = in_domain ? eval(trial, &JtJ_t, &Jtr_t) : std::numeric_limits<double>::infinity();
    if (new_cost <= cost) {
      std::copy(trial, trial + 6, th);
      const bool small = std::abs(step(3)) < 1e-4 && std::abs(step(4)) < 1e-4 && std::abs(step(5)) < 1e-4;
      cost = new_cost;
      JtJ = JtJ_t;
      Jtr = Jtr_t;
      lambda = std::max(lambda / 4, 1e-7);
      if (small) converged = true;
    } else {
      lambda *= 8;
      if (lambda > 1e8) break;
    }
  }
  if (!converged && lambda > 1e8) {
    // Stalled: accept only if the last step sizes were already negligible is unknown; report failure.
    return f;
  }
  f.b0 = th[0];
  f.b1 = th[1];
  f.c = th[2];
  f.a = th[3];
  f.b = th[4];
  f.s = th[5];
  const double dof = std::max(1, n - 6);
  const double s2 = cost / dof;
  Eigen::LDLT<Mat6> ldlt(JtJ);
  if (ldlt.info() != Eigen::Success) return f;
  Vec6 d;
  d << 0, 0, 0, -1, 1, 0;
  const Vec6 x = ldlt.solve(d);
  f.var_w = s2 * d.dot(x);
  // Another line inside the window, beyond either edge?
  int hits = 0;
  for (int k = 0; k < n; ++k) {
    const double u = u0 + k;
    if (u > f.a - 3 * f.s - 2 && u < f.b + 3 * f.s + 2) continue;
    if (p[static_cast<std::size_t>(k)] - (f.b0 + f.b1 * u) > 0.5 * f.c) ++hits;
  }
  f.neighbour = hits >= 2;
  f.ok = std::isfinite(f.var_w) && f.var_w >= 0;
  return f;
}

inline float bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(std::min(y0 + 1, img.rows - 1));
  const int x1 = std::min(x0 + 1, img.cols - 1);
  return static_cast<float>((1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]));
}

struct Station {
  Pt c;
  Pt n;  // unit normal
};

// Tangents/normals from positions by central differences.
std::vector<Station> stations_from(const std::vector<Pt>& p, bool closed) {
  const std::size_t n = p.size();
  std::vector<Station> st(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t i0, i1;
    if (closed) {
      i0 = (i + n - 1) % n;
      i1 = (i + 1) % n;
    } else {
      i0 = i == 0 ? 0 : i - 1;
      i1 = i + 1 >= n ? n - 1 : i + 1;
    }
    double tx = p[i1].x - p[i0].x, ty = p[i1].y - p[i0].y;
    const double norm = std::hypot(tx, ty);
    if (norm > 0) {
      tx /= norm;
      ty /= norm;
    }
    st[i] = {p[i], {-ty, tx}};
  }
  return st;
}

// Measures one station; fills the sample (without s).
void measure_station(const cv::Mat& img, bool light, const Station& st, double half_window, double along_half,
                     double w_guess, std::vector<double>& prof, WidthSample& out) {
  out = WidthSample{};
  out.x_px = st.c.x;
  out.y_px = st.c.y;
  out.nx = st.n.x;
  out.ny = st.n.y;
  out.width_px = kNaN;
  const double tx = st.n.y, ty = -st.n.x;  // tangent
  const int L = static_cast<int>(std::ceil(half_window));
  const int taps = std::max(0, static_cast<int>(std::lround(along_half)));
  // Window corners inside the image?
  for (int sa : {-1, 1})
    for (int sb : {-1, 1}) {
      const double x = st.c.x + sa * L * st.n.x + sb * taps * tx, y = st.c.y + sa * L * st.n.y + sb * taps * ty;
      if (!(x >= 0 && y >= 0 && x <= img.cols - 1.0 && y <= img.rows - 1.0)) {
        out.flags |= kFlagOutOfFrame;
        return;
      }
    }
  prof.assign(static_cast<std::size_t>(2 * L + 1), 0.0);
  const double sign = light ? 1.0 : -1.0;
  const double inv = sign / (2 * taps + 1);
  for (int k = -L; k <= L; ++k) {
    double acc = 0;
    for (int t = -taps; t <= taps; ++t)
      acc += bilinear(img, st.c.x + k * st.n.x + t * tx, st.c.y + k * st.n.y + t * ty);
    prof[static_cast<std::size_t>(k + L)] = acc * inv;
  }
  // A neighbouring line inside the window: cut the window at the valley between them.
  const int n = static_cast<int>(prof.size());
  int lo_k = 0, hi_k = n - 1;
  {
    const int centre = L;
    const int half_w = std::max(1, static_cast<int>(0.5 * w_guess));
    double peak = -1e300, floor_v = 1e300;
    int kpk = centre;
    for (int k = std::max(0, centre - half_w); k <= std::min(n - 1, centre + half_w); ++k)
      if (prof[static_cast<std::size_t>(k)] > peak) {
        peak = prof[static_cast<std::size_t>(k)];
        kpk = k;
      }
    for (double v : prof) floor_v = std::min(floor_v, v);
    const double half = 0.5 * (peak + floor_v);
    auto scan = [&](int dir) {
      int k = kpk;
      while (k + dir >= 0 && k + dir < n && prof[static_cast<std::size_t>(k)] > half) k += dir;
      int valley = k;
      for (; k >= 0 && k < n; k += dir) {
        if (prof[static_cast<std::size_t>(k)] < prof[static_cast<std::size_t>(valley)]) valley = k;
        if (prof[static_cast<std::size_t>(k)] > half) return valley;
      }
      return -1;
    };
    const int vl = scan(-1), vr = scan(+1);
    if (vl >= 0) {
      lo_k = vl;
      out.flags |= kFlagMerged;
    }
    if (vr >= 0) {
      hi_k = vr;
      out.flags |= kFlagMerged;
    }
  }
  if (lo_k > 0 || hi_k < n - 1) {
    prof = std::vector<double>(prof.begin() + lo_k, prof.begin() + hi_k + 1);
  }
  const BarFit f = fit_bar(prof, -L + lo_k, w_guess);
  if (!f.ok) {
    out.flags |= kFlagOccluded;
    return;
  }
  out.width_px = f.b - f.a;
  out.width_stderr_px = std::sqrt(f.var_w);
  out.confidence = 1.0 / (1.0 + (out.width_stderr_px / 0.25) * (out.width_stderr_px / 0.25));
  out.contrast = f.c;
  out.blur_px = f.s;
  const double mid = 0.5 * (f.a + f.b);
  out.x_px = st.c.x + mid * st.n.x;
  out.y_px = st.c.y + mid * st.n.y;
  if (f.neighbour) out.flags |= kFlagMerged;
}

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

cv::Mat load_gray_image(const std::string& path) {
  const cv::Mat img = read_image(path, ImageColor::keep);
  if (img.cols < 16 || img.rows < 16)
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
  const Coarse c = coarse_detect(gray, o, res.warnings);
  res.light_lines = c.light;
  res.coarse_factor = c.f;
  res.noise_sigma = c.noise;

  cv::Mat labels, stats, centroids;
  const int nlab = cv::connectedComponentsWithStats(c.mask, labels, stats, centroids, 8, CV_32S);
  std::vector<int> order;
  const double scale = 0.5 * (c.sx + c.sy);
  const double min_area = std::max(8.0, 1.5 * o.min_length_px / scale);
  for (int i = 1; i < nlab; ++i)
    if (stats.at<int>(i, cv::CC_STAT_AREA) >= min_area) order.push_back(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return stats.at<int>(a, cv::CC_STAT_AREA) > stats.at<int>(b, cv::CC_STAT_AREA); });
  if (static_cast<int>(order.size()) > 4 * o.max_lines) order.resize(static_cast<std::size_t>(4 * o.max_lines));

  std::vector<double> prof;
  for (int lab : order) {
    const int bx = stats.at<int>(lab, cv::CC_STAT_LEFT), by = stats.at<int>(lab, cv::CC_STAT_TOP);
    const int bw = stats.at<int>(lab, cv::CC_STAT_WIDTH), bh = stats.at<int>(lab, cv::CC_STAT_HEIGHT);
    const int pad = 2;
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
      if (hs.at<int>(h, cv::CC_STAT_AREA) > std::max(60.0, 8.0 * dmax * dmax))
        closed = true;
      else
        m.setTo(1, hl == h);
    }
    cv::Mat sk = m.clone();
    thin(sk);
    std::vector<double> dts;
    for (int y = 0; y < sk.rows; ++y)
      for (int x = 0; x < sk.cols; ++x)
        if (sk.at<uchar>(y, x)) dts.push_back(dt.at<float>(y, x));
    if (dts.size() < 3) continue;
    const double w0 = std::max(2.0, (2.0 * median_of(dts) - 0.5) * scale);  // full-res px

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
      for (int y = std::max(0, cy - 2); y <= std::min(sk.rows - 1, cy + 2); ++y)
        for (int x = std::max(0, cx - 2); x <= std::min(sk.cols - 1, cx + 2); ++x) sk.at<uchar>(y, x) = 0;
    }
    const std::vector<int> path = longest_path(sk);
    if (path.size() < 3) continue;
    std::vector<Pt> pts;
    pts.reserve(path.size());
    for (int i : path) {
      const int y = i / sk.cols - pad + by, x = i % sk.cols - pad + bx;
      pts.push_back({(x + 0.5) * c.sx - 0.5, (y + 0.5) * c.sy - 0.5});
    }
    double len = 0;
    for (std::size_t i = 1; i < pts.size(); ++i) len += std::hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y);
    if (len < o.min_length_px) continue;
    if (!closed && len < 2.5 * w0) continue;  // a blob, not a line

    MeasuredLine line;
    line.closed = closed;
    line.bbox = cv::Rect(static_cast<int>(bx * c.sx), static_cast<int>(by * c.sy), static_cast<int>(bw * c.sx),
                         static_cast<int>(bh * c.sy));
    line.touches_frame = bx <= 0 || by <= 0 || bx + bw >= c.mask.cols || by + bh >= c.mask.rows;

    const double step = o.step_px > 0 ? o.step_px : 1.0;
    std::vector<Pt> q = resample(pts, step, closed);
    const double sig = std::max({2.0 * scale, 0.5 * w0, 3.0}) / step;
    smooth_points(q, sig, closed);
    if (!closed) {
      const auto trim = static_cast<std::size_t>(std::ceil((w0 + 2.0 * scale) / step));
      if (q.size() <= 2 * trim + 3) continue;
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

    const double half_window = 0.75 * w0 + 6.0;
    // Pass 1 (every 4th station): re-centre the centreline on the measured mid-points.
    {
      std::vector<Station> st = stations_from(q, closed);
      std::vector<std::pair<double, double>> off(q.size(), {0.0, 0.0});
      std::vector<double> known(q.size(), 0.0);
      WidthSample ws;
      for (std::size_t i = 0; i < st.size(); i += 8) {
        measure_station(gray, c.light, st[i], half_window, o.along_half_px, w0, prof, ws);
        if (ws.flags == 0 && std::isfinite(ws.width_px)) {
          off[i] = {ws.x_px - st[i].c.x, ws.y_px - st[i].c.y};
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
      smooth_seq(wo, sig, closed, get, set);
      smooth_seq(wk, sig, closed, get, set);
      for (std::size_t i = 0; i < q.size(); ++i)
        if (wk[i].first > 1e-3) {
          q[i].x += wo[i].first / wk[i].first;
          q[i].y += wo[i].second / wk[i].first;
        }
    }
    // Pass 2: every station.
    const std::vector<Station> st = stations_from(q, closed);
    line.samples.resize(st.size());
    double s_acc = 0;
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (i > 0) s_acc += std::hypot(st[i].c.x - st[i - 1].c.x, st[i].c.y - st[i - 1].c.y);
      measure_station(gray, c.light, st[i], half_window, o.along_half_px, w0, prof, line.samples[i]);
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
      if (s.contrast < 0.35 * line.median_contrast || s.width_stderr_px > 0.25 * s.width_px) s.flags |= kFlagOccluded;
      if (s.width_px > 1.6 * wmed) s.flags |= kFlagMerged;
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
      res.warnings.push_back(fmt::format("ignored {} faint feature(s) with less than {:.0f} % of the strongest line's "
                                         "contrast (shadows or uneven lighting, not lines)",
                                         dropped, 100 * kFaintFraction));
    }
  }
  std::stable_sort(res.lines.begin(), res.lines.end(),
                   [](const MeasuredLine& a, const MeasuredLine& b) { return a.length_px > b.length_px; });
  return res;
}

}  // namespace tunekit::vision
