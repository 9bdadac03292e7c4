#include "svd_covariance.hpp"

#include <algorithm>
#include <cmath>

#include "lapack.hpp"

namespace tunekit::fitting {

std::optional<std::vector<double>> svd_covariance(const std::vector<double>& jacobian, int rows, int cols,
                                                  double min_reciprocal_condition) {
  if (std::any_of(jacobian.begin(), jacobian.end(), [](double v) { return !std::isfinite(v); })) return std::nullopt;
  // J row-major is J' column-major (cols x rows): its left singular vectors are J's right ones.
  std::vector<double> a(jacobian);  // DGESVD overwrites its matrix
  std::vector<double> sigma(static_cast<std::size_t>(cols)), v(static_cast<std::size_t>(cols) * cols);
  int m = cols, n = rows, info = 0, lwork = -1, one = 1;
  double vt_unused = 0, query = 0;
  dgesvd_("S", "N", &m, &n, a.data(), &m, sigma.data(), v.data(), &m, &vt_unused, &one, &query, &lwork, &info, 1, 1);
  lwork = std::max(1, static_cast<int>(query));
  std::vector<double> work(static_cast<std::size_t>(lwork));
  dgesvd_("S", "N", &m, &n, a.data(), &m, sigma.data(), v.data(), &m, &vt_unused, &one, work.data(), &lwork, &info, 1,
          1);
  if (info != 0) return std::nullopt;
  const double min_ratio = std::sqrt(min_reciprocal_condition);
  const auto k = static_cast<std::size_t>(cols);
  std::vector<double> cov(k * k, 0.0);
  for (std::size_t i = 0; i < k; ++i) {
    if (!(sigma[i] / sigma[0] >= min_ratio)) return std::nullopt;
    const double w = 1.0 / (sigma[i] * sigma[i]);
    const double* vi = v.data() + i * k;  // column i of V
    for (std::size_t r = 0; r < k; ++r)
      for (std::size_t c = r; c < k; ++c) cov[r * k + c] += w * (vi[r] * vi[c]);
  }
  for (std::size_t r = 0; r < k; ++r)  // symmetric to the bit
    for (std::size_t c = 0; c < r; ++c) cov[r * k + c] = cov[c * k + r];
  return cov;
}

}  // namespace tunekit::fitting
