// Line edge profile: the width at one station of the centreline. The photo is sampled across
// the line (averaged along it) for the start values and to cut off a neighbouring line inside the
// window at the valley between them; then a blurred bar, I(u) = b0 + b1 u + c [E(u; a) - E(u; b)],
// E the edge blurred by a Gaussian of sigma s and averaged over a pixel's width, is fitted by
// Levenberg-Marquardt to the pixels themselves (each at its own offset u across the line, weighted
// as the averaging along the line weighs it): the width is b - a with its standard error from the
// fit.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "tunekit/fitting/levenberg_marquardt.hpp"

#include "line_width_stages.hpp"

namespace tunekit::vision::detail {
namespace {

// Window across the line: the bar covers +-w0/2; 0.75 w0 leaves a quarter width of bed beyond
// each edge, and 6 px more hold the edge's blur tail (3 sigma of the largest 2 px start value of
// the blur) and the baseline samples at the window's ends.
constexpr double kHalfWindowPerWidth = 0.75;
constexpr double kHalfWindowMarginPx = 6.0;
// The bar model has 6 parameters: fewer than 10 samples across the line leave too few degrees
// of freedom for its standard error.
constexpr int kBarMinSamples = 10;
// Start values of the baseline: the mean of 3 samples at each end of the window.
constexpr int kBaselineEndSamples = 3;
// Edges start at the half-maximum crossings (a blurred step edge is at half its height); the
// peak is looked for within half a width of the centre.
constexpr double kHalfMaximum = 0.5;
constexpr double kPeakSearchPerWidth = 0.5;
// Start value of the blur: a twentieth of the width, within 0.4-2 px (a focused camera's edge
// spread is about a pixel).
constexpr double kBlurStartPerWidth = 0.25 * 0.2;
constexpr double kBlurStartMinPx = 0.4;
constexpr double kBlurStartMaxPx = 2.0;
// Beyond 6 sigma of a pixel's edge Phi is 0 or 1 to within 1e-9: the edge term is not evaluated
// there.
constexpr double kEdgeTailSigmas = 6.0;
// The bar fit's convergence (bar_tolerances): at most 40 iterations bound the cost of a station
// that does not settle.
constexpr double kBarFunctionTolerance = 1e-10;
constexpr double kBarParameterTolerance = 1e-8;
constexpr int kBarMaxIterations = 40;
// Domain of the bar: blur above 0.1 px (sharper is below the sampling and makes Phi a step the
// Jacobian cannot follow), width above 1 px, positive contrast, both edges inside the window,
// and blur below half the width plus 2 px (otherwise the "bar" is a blurred bump whose edges
// are not determined).
constexpr double kBarMinBlurPx = 0.1;
constexpr double kBarMinWidthPx = 1.0;
constexpr double kBarMaxBlurPerWidth = 0.5;
constexpr double kBarMaxBlurMarginPx = 2.0;
// Another line inside the window: at least 2 samples beyond 3 blur sigmas + 2 px of the edges
// rising above half the bar's contrast.
constexpr double kNeighbourEdgeSigmas = 3.0;
constexpr double kNeighbourEdgeMarginPx = 2.0;
constexpr double kNeighbourContrastFraction = 0.5;
constexpr int kNeighbourMinSamples = 2;
// Confidence 1 / (1 + (stderr / 0.25 px)^2): a sample whose width is known to a quarter pixel
// has confidence 0.5; a quarter pixel is the spread the straight-line accuracy target allows
// (std <= 0.25 px).
constexpr double kConfidenceStderrPx = 0.25;

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

// An edge at `edge` (px) blurred by a Gaussian of sigma s (px), as a pixel centred at u records
// it: the blurred step averaged over the pixel's width across the line,
// E = s [psi(z+) - psi(z-)], z+- = (u +- 1/2 - edge) / s, psi(z) = z Phi(z) + phi(z) (a camera
// pixel integrates the light over its area; for a line along a pixel axis this is exact, at other
// angles the pixel's footprint across the line is a trapezoid of the same variance). Its
// derivatives: dE/d(edge) = -(Phi(z+) - Phi(z-)), dE/ds = phi(z+) - phi(z-).
struct PixelEdge {
  double e = 0, d_edge = 0, d_s = 0;
  bool near = false;  // within reach of the edge (the derivatives are nonzero)
};

inline PixelEdge pixel_edge(double u, double edge, double s) {
  PixelEdge r;
  const double inv_s = 1.0 / s;
  const double zp = (u + 0.5 - edge) * inv_s, zm = (u - 0.5 - edge) * inv_s;
  if (zm > kEdgeTailSigmas) {
    r.e = 1.0;
    return r;
  }
  if (zp < -kEdgeTailSigmas) return r;
  double cp, fp, cm, fm;
  normal_cdf_pdf(zp, cp, fp);
  normal_cdf_pdf(zm, cm, fm);
  r.e = s * ((zp * cp + fp) - (zm * cm + fm));
  r.d_edge = -(cp - cm);
  r.d_s = fp - fm;
  r.near = true;
  return r;
}

struct BarFit {
  bool ok = false;
  double b0 = 0, b1 = 0, c = 0, a = 0, b = 0, s = 1;
  double var_w = kNaN;
  bool neighbour = false;
};

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using BarParams = std::array<double, 6>;  // b0, b1, c, a, b, s

// Start values of the bar from the interpolated profile p[k] at u = u0 + k: the baseline through
// the means of the window's ends, the contrast at the peak near the centre, the edges at the
// half-maximum crossings and the blur from the width. False when no bar stands out.
bool bar_start(const std::vector<double>& p, double u0, double w_guess, BarParams& th) {
  const int n = static_cast<int>(p.size());
  const int e = kBaselineEndSamples;
  double ml = 0, mr = 0;
  for (int k = 0; k < e; ++k) {
    ml += p[static_cast<std::size_t>(k)];
    mr += p[static_cast<std::size_t>(n - 1 - k)];
  }
  ml /= e;
  mr /= e;
  const double ul = u0 + (e - 1) / 2.0, ur = u0 + n - 1 - (e - 1) / 2.0;
  th[1] = (mr - ml) / (ur - ul);
  th[0] = ml - th[1] * ul;
  // Peak in the central region.
  const int half = std::max(1, static_cast<int>(kPeakSearchPerWidth * w_guess));
  const int mid = static_cast<int>(std::lround(-u0));
  int kp = std::clamp(mid, 0, n - 1);
  for (int k = std::max(0, mid - half); k <= std::min(n - 1, mid + half); ++k)
    if (p[static_cast<std::size_t>(k)] - (th[0] + th[1] * (u0 + k)) >
        p[static_cast<std::size_t>(kp)] - (th[0] + th[1] * (u0 + kp)))
      kp = k;
  auto base = [&](int k) { return th[0] + th[1] * (u0 + k); };
  const double c0 = p[static_cast<std::size_t>(kp)] - base(kp);
  if (!(c0 > 0)) return false;
  auto above = [&](int k) { return p[static_cast<std::size_t>(k)] - base(k) > kHalfMaximum * c0; };
  int kl = kp;
  while (kl > 0 && above(kl - 1)) --kl;
  int kr = kp;
  while (kr < n - 1 && above(kr + 1)) ++kr;
  if (kl == 0 || kr == n - 1) return false;
  auto cross = [&](int k_in, int k_out) {
    const double vi = p[static_cast<std::size_t>(k_in)] - base(k_in) - kHalfMaximum * c0;
    const double vo = p[static_cast<std::size_t>(k_out)] - base(k_out) - kHalfMaximum * c0;
    const double t = vi / (vi - vo);
    return u0 + k_in + t * (k_out - k_in);
  };
  th[2] = c0;
  th[3] = cross(kl, kl - 1);
  th[4] = cross(kr, kr + 1);
  th[5] = std::clamp(kBlurStartPerWidth * (th[4] - th[3]), kBlurStartMinPx, kBlurStartMaxPx);
  return true;
}

// The bar's domain inside a window of n samples from u0 (see kBarMinBlurPx).
bool bar_in_domain(std::span<const double> t, double u0, int n) {
  return t[5] > kBarMinBlurPx && t[4] - t[3] > kBarMinWidthPx && t[2] > 0 && t[3] > u0 && t[4] < u0 + n - 1 &&
         t[5] < kBarMaxBlurPerWidth * (t[4] - t[3]) + kBarMaxBlurMarginPx;
}

// The weighted normal equations J'WJ and J'Wr of the bar at t over the pixels (du, dv, dw) and
// its weighted residual sum of squares. The sums are kept in locals (the lower triangle) and
// written once: accumulated into the output matrices, every term was a load and a store.
double bar_normal_equations(std::span<const double> t, const std::vector<double>& du, const std::vector<double>& dv,
                            const std::vector<double>& dw, Mat6& JtJ, Vec6& Jtr) {
  double rss = 0;
  double n[6][6] = {};
  double g[6] = {};
  for (std::size_t k = 0; k < du.size(); ++k) {
    const double u = du[k], w = dw[k];
    const PixelEdge ea = pixel_edge(u, t[3], t[5]), eb = pixel_edge(u, t[4], t[5]);
    const double r = t[0] + t[1] * u + t[2] * (ea.e - eb.e) - dv[k];
    rss += w * r * r;
    const double j[6] = {1.0, u, ea.e - eb.e, t[2] * ea.d_edge, -t[2] * eb.d_edge, t[2] * (ea.d_s - eb.d_s)};
    const int m = (ea.near || eb.near) ? 6 : 3;  // far from both edges only the background and contrast terms move
    for (int a = 0; a < m; ++a) {
      const double wj = w * j[a];
      g[a] += wj * r;
      for (int b = 0; b <= a; ++b) n[a][b] += wj * j[b];
    }
  }
  for (int a = 0; a < 6; ++a) {
    Jtr(a) = g[a];
    for (int b = 0; b <= a; ++b) JtJ(a, b) = JtJ(b, a) = n[a][b];
  }
  return rss;
}

// The variance of the width b - a from the fit's normal equations and cost (weighted sum of
// squares over the pixels' total weight less 6 parameters); NaN when J'WJ is singular.
double width_variance(const Mat6& JtJ, double cost, const std::vector<double>& dw) {
  double w_sum = 0;
  for (double w : dw) w_sum += w;
  const double dof = std::max(1.0, w_sum - 6);
  const double s2 = cost / dof;
  Eigen::LDLT<Mat6> ldlt(JtJ);
  if (ldlt.info() != Eigen::Success) return kNaN;
  Vec6 d;
  d << 0, 0, 0, -1, 1, 0;
  const Vec6 x = ldlt.solve(d);
  return s2 * d.dot(x);
}

// Another line inside the window, beyond either edge of the fitted bar?
bool neighbour_inside(const std::vector<double>& p, double u0, const BarFit& f) {
  int hits = 0;
  for (int k = 0; k < static_cast<int>(p.size()); ++k) {
    const double u = u0 + k;
    if (u > f.a - kNeighbourEdgeSigmas * f.s - kNeighbourEdgeMarginPx &&
        u < f.b + kNeighbourEdgeSigmas * f.s + kNeighbourEdgeMarginPx)
      continue;
    if (p[static_cast<std::size_t>(k)] - (f.b0 + f.b1 * u) > kNeighbourContrastFraction * f.c) ++hits;
  }
  return hits >= kNeighbourMinSamples;
}

// Convergence tests of the bar fit: those of fitting's Levenberg-Marquardt iteration with
// the cost or the parameters changing by less than 1e-10 or 1e-8 of themselves (the edges then
// move far less than the 0.1 px bias the width is measured to); at most kBarMaxIterations.
fitting::lm_detail::Tolerances bar_tolerances() {
  fitting::lm_detail::Tolerances tol;
  tol.function = kBarFunctionTolerance;
  tol.parameter = kBarParameterTolerance;
  tol.max_iterations = kBarMaxIterations;
  return tol;
}

// Fits I(u) = b0 + b1 u + c [Phi((u-a)/s) - Phi((u-b)/s)] to the pixels (du[i], dv[i]): their
// offsets across the line and values. The start values and the neighbour check come from the
// interpolated profile p[k] at u = u0 + k. The fit is fitting's Levenberg-Marquardt iteration
// (levenberg_marquardt.hpp) to its convergence tests; a trial outside the bar's domain counts as
// one that raised the cost.
BarFit fit_bar(const std::vector<double>& p, double u0, double w_guess, const std::vector<double>& du,
               const std::vector<double>& dv, const std::vector<double>& dw) {
  BarFit f;
  const int n = static_cast<int>(p.size());
  BarParams th{};
  if (n < kBarMinSamples || !bar_start(p, u0, w_guess, th)) return f;
  auto normal_equations = [&](std::span<const double> t, Mat6& JtJ, Vec6& Jtr) {
    if (!bar_in_domain(t, u0, n)) return std::numeric_limits<double>::infinity();
    return bar_normal_equations(t, du, dv, dw, JtJ, Jtr);
  };
  namespace lm = fitting::lm_detail;
  lm::Equations<Mat6, Vec6> at;
  at.cost = bar_normal_equations(th, du, dv, dw, at.N, at.g);
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  const BarParams lo{-kUnbounded, -kUnbounded, -kUnbounded, -kUnbounded, -kUnbounded, -kUnbounded};
  const BarParams hi{kUnbounded, kUnbounded, kUnbounded, kUnbounded, kUnbounded, kUnbounded};
  const std::array<bool, 6> fixed{};
  const lm::Confirmed end =
      lm::confirm(std::span<double>(th), lo, hi, fixed, normal_equations, at, lm::kInitialDamping, bar_tolerances());
  // Stalled: whether the last steps were already negligible is unknown; report failure.
  if (end.end == lm::ConfirmEnd::no_decrease) return f;
  f.b0 = th[0];
  f.b1 = th[1];
  f.c = th[2];
  f.a = th[3];
  f.b = th[4];
  f.s = th[5];
  f.var_w = width_variance(at.N, at.cost, dw);
  f.neighbour = neighbour_inside(p, u0, f);
  f.ok = std::isfinite(f.var_w) && f.var_w >= 0;
  return f;
}

}  // namespace

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

double measuring_half_window(double w0) { return kHalfWindowPerWidth * w0 + kHalfWindowMarginPx; }

namespace {

// The window of +-L samples across the line and +-taps along it at the station lies inside the
// image.
bool window_in_frame(const cv::Mat& img, const Station& st, int L, int taps) {
  const double tx = st.n.y, ty = -st.n.x;  // tangent
  for (int sa : {-1, 1})
    for (int sb : {-1, 1}) {
      const double x = st.c.x + sa * L * st.n.x + sb * taps * tx, y = st.c.y + sa * L * st.n.y + sb * taps * ty;
      if (!(x >= 0 && y >= 0 && x <= img.cols - 1.0 && y <= img.rows - 1.0)) return false;
    }
  return true;
}

// The profile across the line at offsets -L..L, each the mean of 2 taps + 1 bilinear samples
// along it, times `sign` (a dark line on a light bed turned into a bright bar).
void sample_across(const cv::Mat& img, const Station& st, int L, int taps, double sign, std::vector<double>& prof) {
  const double tx = st.n.y, ty = -st.n.x;  // tangent
  prof.assign(static_cast<std::size_t>(2 * L + 1), 0.0);
  const double inv = sign / (2 * taps + 1);
  for (int k = -L; k <= L; ++k) {
    double acc = 0;
    for (int t = -taps; t <= taps; ++t)
      acc += bilinear(img, st.c.x + k * st.n.x + t * tx, st.c.y + k * st.n.y + t * ty);
    prof[static_cast<std::size_t>(k + L)] = acc * inv;
  }
}

// A neighbouring line inside the window: the window is cut at the valley between them (the
// lowest sample between this line's half-maximum and the next rise above it). The first and the
// last sample kept, [lo_k, hi_k]; kFlagMerged in `flags` when a neighbour was cut off.
std::pair<int, int> cut_at_neighbours(const std::vector<double>& prof, int centre, double w_guess,
                                      std::uint8_t& flags) {
  const int n = static_cast<int>(prof.size());
  int lo_k = 0, hi_k = n - 1;
  const int half_w = std::max(1, static_cast<int>(kPeakSearchPerWidth * w_guess));
  double peak = -1e300, floor_v = 1e300;
  int kpk = centre;
  for (int k = std::max(0, centre - half_w); k <= std::min(n - 1, centre + half_w); ++k)
    if (prof[static_cast<std::size_t>(k)] > peak) {
      peak = prof[static_cast<std::size_t>(k)];
      kpk = k;
    }
  for (double v : prof) floor_v = std::min(floor_v, v);
  const double half = kHalfMaximum * (peak + floor_v);
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
    flags |= kFlagMerged;
  }
  if (vr >= 0) {
    hi_k = vr;
    flags |= kFlagMerged;
  }
  return {lo_k, hi_k};
}

// The pixels a bar fit reads: offset across the line, value times `sign`, and weight (how much
// the averaging along the line weighs the pixel).
struct AcrossPixels {
  std::vector<double> du, dv, dw;
};

// The pixels within [u_lo, u_hi] across the line and within the taps along it. The fit reads the
// pixels themselves, each at its own offset across the line: an interpolated sample between two
// pixels is not a value the bar model describes, and it biases the edges by up to a few
// hundredths of a pixel depending on where they fall between pixel centres.
AcrossPixels pixels_across(const cv::Mat& img, const Station& st, int L, int taps, double u_lo, double u_hi,
                           double sign) {
  AcrossPixels px;
  const double tx = st.n.y, ty = -st.n.x;  // tangent
  const double t_half = taps + 1.0;
  const double ex = L * std::abs(st.n.x) + t_half * std::abs(tx), ey = L * std::abs(st.n.y) + t_half * std::abs(ty);
  const int x0 = std::max(0, static_cast<int>(std::floor(st.c.x - ex)));
  const int x1 = std::min(img.cols - 1, static_cast<int>(std::ceil(st.c.x + ex)));
  const int y0 = std::max(0, static_cast<int>(std::floor(st.c.y - ey)));
  const int y1 = std::min(img.rows - 1, static_cast<int>(std::ceil(st.c.y + ey)));
  for (int y = y0; y <= y1; ++y) {
    const float* row = img.ptr<float>(y);
    for (int x = x0; x <= x1; ++x) {
      const double rx = x - st.c.x, ry = y - st.c.y;
      const double u = rx * st.n.x + ry * st.n.y, t = rx * tx + ry * ty;
      if (u < u_lo || u > u_hi || !(std::abs(t) < t_half)) continue;
      double w = 0;
      for (int k = -taps; k <= taps; ++k) w += std::max(0.0, 1.0 - std::abs(t - k));
      px.du.push_back(u);
      px.dv.push_back(sign * row[x]);
      px.dw.push_back(w);
    }
  }
  return px;
}

// The sample from a fitted bar: width, its standard error and confidence, contrast, blur, and
// the bar's middle as the position.
void record_bar(const BarFit& f, const Station& st, WidthSample& out) {
  out.width_px = f.b - f.a;
  out.width_stderr_px = std::sqrt(f.var_w);
  out.confidence =
      1.0 / (1.0 + (out.width_stderr_px / kConfidenceStderrPx) * (out.width_stderr_px / kConfidenceStderrPx));
  out.contrast = f.c;
  out.blur_px = f.s;
  const double mid = 0.5 * (f.a + f.b);
  out.x_px = st.c.x + mid * st.n.x;
  out.y_px = st.c.y + mid * st.n.y;
  if (f.neighbour) out.flags |= kFlagMerged;
}

}  // namespace

void measure_station(const cv::Mat& img, bool light, const Station& st, double half_window, double along_half,
                     double w_guess, std::vector<double>& prof, WidthSample& out) {
  out = WidthSample{};
  out.x_px = st.c.x;
  out.y_px = st.c.y;
  out.nx = st.n.x;
  out.ny = st.n.y;
  out.width_px = kNaN;
  const int L = static_cast<int>(std::ceil(half_window));
  const int taps = std::max(0, static_cast<int>(std::lround(along_half)));
  if (!window_in_frame(img, st, L, taps)) {
    out.flags |= kFlagOutOfFrame;
    return;
  }
  const double sign = light ? 1.0 : -1.0;
  sample_across(img, st, L, taps, sign, prof);
  const int n = static_cast<int>(prof.size());
  const auto [lo_k, hi_k] = cut_at_neighbours(prof, L, w_guess, out.flags);
  if (lo_k > 0 || hi_k < n - 1) {
    prof = std::vector<double>(prof.begin() + lo_k, prof.begin() + hi_k + 1);
  }
  const AcrossPixels px = pixels_across(img, st, L, taps, -L + lo_k, -L + hi_k, sign);
  const BarFit f = fit_bar(prof, -L + lo_k, w_guess, px.du, px.dv, px.dw);
  if (!f.ok) {
    out.flags |= kFlagOccluded;
    return;
  }
  record_bar(f, st, out);
}

void measure_stations(const cv::Mat& img, bool light, const std::vector<Station>& st, std::size_t stride,
                      double half_window, double along_half, double w_guess, std::vector<WidthSample>& out) {
  out.assign(st.size(), WidthSample{});
  const int n = static_cast<int>((st.size() + stride - 1) / stride);
  cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& r) {
    std::vector<double> prof;
    for (int k = r.start; k < r.end; ++k) {
      const std::size_t i = static_cast<std::size_t>(k) * stride;
      measure_station(img, light, st[i], half_window, along_half, w_guess, prof, out[i]);
    }
  });
}

}  // namespace tunekit::vision::detail
