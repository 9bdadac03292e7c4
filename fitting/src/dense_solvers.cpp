#include "tunekit/fitting/dense_solvers.hpp"

#include <Eigen/Dense>

namespace tunekit::fitting {

Eigen::VectorXd least_squares_solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  return A.colPivHouseholderQr().solve(b);
}

Eigen::VectorXd symmetric_eigenvalues(const Eigen::MatrixXd& S) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S, Eigen::EigenvaluesOnly).eigenvalues();
}

Eigen::MatrixXd inverse(const Eigen::MatrixXd& M) { return M.inverse(); }

std::optional<Eigen::VectorXd> ldlt_solve(const Eigen::MatrixXd& S, const Eigen::VectorXd& b) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  return Eigen::VectorXd(ldlt.solve(b));
}

}  // namespace tunekit::fitting
