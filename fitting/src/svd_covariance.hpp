#pragma once
// The parameters' covariance (J'J)^-1 from the singular value decomposition of the Jacobian J at
// a least-squares solution: V diag(1 / sigma_i^2) V', with the rank test of Ceres Solver's
// Covariance with DENSE_SVD and null_space_rank 0 (Agarwal, Mierle and others, Ceres Solver
// 2.1, 2022). The decomposition is LAPACK's DGESVD without the singular vectors on J's long side:
// Ceres forms those too (as many rows as J, never used), which on a record of 120k samples was
// most of its time.
#include <optional>
#include <vector>

namespace tunekit::fitting {

/// (J'J)^-1 as a row-major cols x cols matrix, J the rows x cols Jacobian in row-major order
/// (rows >= cols, as a cost function writes it). Nothing when J is not finite, the
/// decomposition fails, or a singular value is below sqrt(min_reciprocal_condition) times the
/// largest (the reciprocal condition number of J'J below min_reciprocal_condition).
std::optional<std::vector<double>> svd_covariance(const std::vector<double>& jacobian, int rows, int cols,
                                                  double min_reciprocal_condition);

}  // namespace tunekit::fitting
