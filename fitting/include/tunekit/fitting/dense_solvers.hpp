#pragma once
// Dense solvers that several libraries need, compiled once in this library. Each of Eigen's
// decompositions costs seconds of compile time in every translation unit that instantiates it
// (docs/benchmarks.md); these functions compute exactly what calling Eigen directly on
// Eigen::MatrixXd computes, so a caller gets the same numbers without the instantiation.

#include <optional>

#include <Eigen/Core>

namespace tunekit::fitting {

/// The least-squares solution x of A x = b (a row of A per observation), by Eigen's
/// column-pivoted Householder QR (A.colPivHouseholderQr().solve(b)).
Eigen::VectorXd least_squares_solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b);

/// The eigenvalues of the symmetric matrix S (its lower triangle is read), in increasing order
/// (Eigen's SelfAdjointEigenSolver without eigenvectors).
Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& S);

/// The inverse of the square, invertible matrix M (Eigen's partial-pivoting LU: M.inverse()).
Eigen::MatrixXd inverse(const Eigen::MatrixXd& M);

/// The solution x of S x = b for a symmetric positive semi-definite S, by Eigen's LDLT; nothing
/// when the factorisation fails.
std::optional<Eigen::VectorXd> ldlt_solve(const Eigen::MatrixXd& S, const Eigen::VectorXd& b);

}  // namespace tunekit::fitting
