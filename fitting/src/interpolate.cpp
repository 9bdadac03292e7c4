#include "tunekit/fitting/interpolate.hpp"

#include <algorithm>

namespace tunekit::fitting {

double interp_linear(std::span<const double> xs, std::span<const double> ys, double x) {
  if (x <= xs.front()) return ys.front();
  if (x >= xs.back()) return ys.back();
  const auto i = static_cast<std::size_t>(std::upper_bound(xs.begin(), xs.end(), x) - xs.begin());
  const double t = (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
  return ys[i - 1] + t * (ys[i] - ys[i - 1]);
}

std::vector<double> interp_linear(std::span<const double> xs, std::span<const double> ys, std::span<const double> xq) {
  std::vector<double> y(xq.size());
  for (std::size_t i = 0; i < xq.size(); ++i) y[i] = interp_linear(xs, ys, xq[i]);
  return y;
}

}  // namespace tunekit::fitting
