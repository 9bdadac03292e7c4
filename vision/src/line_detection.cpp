// Line detection, the coarse pass of measure_line_widths: on a downsampled copy of the photo,
// model the bed (lighting surface plus morphology), decide whether lines are lighter or darker
// than the bed, and threshold the contrast into a mask of line pixels. Widths are measured at
// full resolution afterwards (line_edge_profile.cpp), so this pass only has to find the lines.

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include "line_width_stages.hpp"
#include "tunekit/fitting/dense_solvers.hpp"

namespace tunekit::vision::detail {
namespace {

// The coarse pass works on at most about this many pixels: detection (lighting fit, morphology,
// thinning, shortest paths) then costs the same for a 2 MP and a 50 MP photo, and a line a few
// full-resolution pixels wide still covers a coarse pixel.
constexpr double kCoarseMaxPixels = 1.2e6;

// Lighting surface: total degree 4 (15 terms) from a 24 px short side (>= 576 samples, about 36
// per term), degree 2 from 8 px (64 samples for 6 terms), a constant below.
constexpr int kLightingQuarticMinSide = 24;
constexpr int kLightingQuadraticMinSide = 8;
// About 3000 samples are plenty for 15 coefficients and keep the fit to a millisecond or two.
constexpr double kLightingSamples = 3000.0;
// With fewer than 3 usable samples per term (most of the frame excluded) the surface is not
// determined robustly; the mean level is used instead.
constexpr std::size_t kLightingMinSamplesPerTerm = 3;
// Reweighting rounds: the outlier set (lines, specks) settles within a few; six bound the cost.
constexpr int kLightingReweightRounds = 6;
// Floor of the robust sigma so a noise-free synthetic bed does not reject every sample.
constexpr double kLightingMinSigma = 1e-6;
// Samples further than this many robust sigmas from the surface are lines or dirt, not lighting
// (2.5 sigma keeps 98.8 % of normally distributed bed noise).
constexpr double kLightingOutlierSigmas = 2.5;

// The background model runs on a further-reduced copy whose short side keeps at least this many
// samples (the lighting and bed texture it follows are smooth at that scale) ...
constexpr int kBackgroundMinSide = 48;
// ... reduced by at most this factor, so the local lighting and bed texture the morphology
// below is meant to follow keep some detail.
constexpr int kBackgroundMaxReduction = 4;
// Morphology window (square, odd, px of the reduced copy): half its short side, at least 3 px
// and at most 21 px. Closing (or opening) removes features narrower than the window -- the
// lines -- and leaves the bed; a larger window would follow the lighting less closely.
constexpr int kMorphKernelMinPx = 3;
constexpr int kMorphKernelMaxPx = 21;
// The blocky morphology result is smoothed with a Gaussian of a quarter of the window (at least
// 1 px) before it becomes the background.
constexpr double kBackgroundBlurPerKernel = 4.0;
constexpr double kBackgroundMinBlurPx = 1.0;

// Polarity vote: only residuals beyond 4 robust sigmas count (bed noise almost never reaches
// them, lines do); every 2nd pixel in each direction is enough for the sigma.
constexpr double kPolarityTailSigmas = 4.0;
constexpr int kPolaritySubsample = 2;
// Noise of the contrast image from every 3rd pixel in each direction (a ninth of the image).
constexpr int kNoiseSubsample = 3;
// Nothing is a line unless the strongest contrast is 8 noise sigmas above the bed: below that the
// mask would hold noise and texture.
constexpr double kMinPeakSnr = 8.0;
// The mask threshold is Otsu's split of the contrast, raised to at least 5 noise sigmas so that
// noise on an almost empty bed does not enter the mask.
constexpr double kMaskMinSnr = 5.0;
// Otsu runs on an 8-bit copy of the contrast scaled to 0..255.
constexpr double kOtsuLevels = 255.0;

int pick_coarse_factor(int w, int h) {
  const double px = static_cast<double>(w) * h;
  return std::max(1, static_cast<int>(std::ceil(std::sqrt(px / kCoarseMaxPixels))));
}

// Robust polynomial surface (total degree up to 4) through a small CV_32F image: iteratively
// reweighted least squares that drops pixels more than kLightingOutlierSigmas robust sigmas from
// the surface (the printed lines, dirt), so it describes the bed's lighting only. Nonzero pixels
// of `exclude` (CV_8U, same size, may be empty) are not used (a scale target).
cv::Mat fit_lighting(const cv::Mat& img, const cv::Mat& exclude) {
  const int W = img.cols, H = img.rows;
  const int degree =
      std::min(W, H) >= kLightingQuarticMinSide ? 4 : (std::min(W, H) >= kLightingQuadraticMinSide ? 2 : 0);
  std::vector<std::pair<int, int>> terms;
  for (int d = 0; d <= degree; ++d)
    for (int i = 0; i <= d; ++i) terms.emplace_back(d - i, i);
  const auto nt = static_cast<Eigen::Index>(terms.size());
  auto coord = [](int v, int n) { return n > 1 ? 2.0 * v / (n - 1) - 1.0 : 0.0; };
  auto basis = [&](double u, double v, double* out) {
    const double pu[5] = {1, u, u * u, u * u * u, u * u * u * u}, pv[5] = {1, v, v * v, v * v * v, v * v * v * v};
    for (std::size_t t = 0; t < terms.size(); ++t) out[t] = pu[terms[t].first] * pv[terms[t].second];
  };
  const int step = std::max(1, static_cast<int>(std::ceil(std::sqrt(static_cast<double>(W) * H / kLightingSamples))));
  std::vector<std::pair<int, int>> at;
  for (int y = step / 2; y < H; y += step)
    for (int x = step / 2; x < W; x += step)
      if (exclude.empty() || exclude.at<uchar>(y, x) == 0) at.emplace_back(x, y);
  if (at.size() < kLightingMinSamplesPerTerm * terms.size()) return cv::Mat(H, W, CV_32F, cv::Scalar(cv::mean(img)[0]));
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
  for (int it = 0; it < kLightingReweightRounds; ++it) {
    const Eigen::MatrixXd AtA = A.transpose() * wt.asDiagonal() * A;
    const Eigen::VectorXd Atb = A.transpose() * wt.cwiseProduct(vals);
    const auto solved = fitting::ldlt_solve(AtA, Atb);
    if (!solved) break;
    coef = *solved;
    const Eigen::VectorXd res = vals - A * coef;
    std::vector<double> kept;
    for (Eigen::Index i = 0; i < n; ++i)
      if (wt(i) != 0) kept.push_back(std::abs(res(i)));
    const double sigma = std::max(kLightingMinSigma, kMadToSigma * median_of(kept));
    for (Eigen::Index i = 0; i < n; ++i) wt(i) = std::abs(res(i)) <= kLightingOutlierSigmas * sigma ? 1.0 : 0.0;
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

}  // namespace

Coarse coarse_detect(const cv::Mat& gray, const LineWidthOptions& o, std::vector<std::string>& warnings) {
  Coarse c;
  c.f = o.coarse_factor > 0 ? o.coarse_factor : pick_coarse_factor(gray.cols, gray.rows);
  cv::Mat coarse;
  if (c.f > 1)
    cv::resize(gray, coarse, cv::Size(std::max(1, gray.cols / c.f), std::max(1, gray.rows / c.f)), 0, 0,
               cv::INTER_AREA);
  else coarse = gray;
  c.sx = static_cast<double>(gray.cols) / coarse.cols;
  c.sy = static_cast<double>(gray.rows) / coarse.rows;

  // Background on a further-reduced copy, in two stages. (a) A smooth lighting surface: a
  // low-order polynomial fitted robustly (lines and specks are outliers), which follows
  // vignetting and a lamp at one side right up to the image border, where morphology alone
  // is biased (its window runs out of the image and it mistakes the darkening corners for
  // features). (b) Morphology on what remains: closing removes dark features, opening light
  // ones, so local lighting the polynomial cannot follow (glare, bed texture) drops out too.
  const int g = std::clamp(std::min(coarse.cols, coarse.rows) / kBackgroundMinSide, 1, kBackgroundMaxReduction);
  cv::Mat tiny;
  if (g > 1)
    cv::resize(coarse, tiny, cv::Size(std::max(1, coarse.cols / g), std::max(1, coarse.rows / g)), 0, 0,
               cv::INTER_AREA);
  else tiny = coarse;
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
  int k = std::min(kMorphKernelMaxPx, std::max(kMorphKernelMinPx, (std::min(tiny.cols, tiny.rows) / 2) | 1));
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
    for (int y = 0; y < resid.rows; y += kPolaritySubsample) {
      const float* row = resid.ptr<float>(y);
      for (int x = 0; x < resid.cols; x += kPolaritySubsample) absr.push_back(std::abs(row[x]));
    }
    const double cut = kPolarityTailSigmas * kMadToSigma * median_of(absr);
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
  cv::GaussianBlur(bg_tiny, bg_tiny, cv::Size(0, 0), std::max(kBackgroundMinBlurPx, k / kBackgroundBlurPerKernel), 0,
                   cv::BORDER_REPLICATE);
  bg_tiny += lighting;
  cv::Mat bg;
  cv::resize(bg_tiny, bg, coarse.size(), 0, 0, cv::INTER_LINEAR);
  c.contrast = c.light ? cv::Mat(coarse - bg) : cv::Mat(bg - coarse);

  // Robust noise (MAD) on a subsample, then Otsu on the positive contrast.
  std::vector<double> sub;
  sub.reserve(static_cast<std::size_t>(c.contrast.total() / kNoiseSubsample + 1));
  for (int y = 0; y < c.contrast.rows; y += kNoiseSubsample) {
    const float* row = c.contrast.ptr<float>(y);
    for (int x = 0; x < c.contrast.cols; x += kNoiseSubsample) sub.push_back(row[x]);
  }
  const double med = median_of(sub);
  for (auto& v : sub) v = std::abs(v - med);
  c.noise = kMadToSigma * median_of(sub);
  double maxc = 0;
  cv::minMaxLoc(c.contrast, nullptr, &maxc);
  c.mask = cv::Mat::zeros(coarse.size(), CV_8U);
  if (!(maxc > 0) || maxc < kMinPeakSnr * c.noise) {
    warnings.push_back(
        fmt::format("no feature stands out of the background (largest contrast {:.3g}, noise {:.3g})", maxc, c.noise));
    return c;
  }
  cv::Mat c8;
  c.contrast.convertTo(c8, CV_8U, kOtsuLevels / maxc);
  const double t8 = cv::threshold(c8, c8, 0, kOtsuLevels, cv::THRESH_BINARY | cv::THRESH_OTSU);
  const double thr = std::max(t8 * maxc / kOtsuLevels, kMaskMinSnr * c.noise);
  c.mask = c.contrast > thr;
  if (!o.exclude_mask.empty()) {
    cv::Mat ex;
    cv::resize(o.exclude_mask, ex, coarse.size(), 0, 0, cv::INTER_NEAREST);
    c.mask.setTo(0, ex);
  }
  return c;
}

}  // namespace tunekit::vision::detail
