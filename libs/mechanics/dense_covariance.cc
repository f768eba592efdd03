#include "libs/mechanics/dense_covariance.h"

#include <ceres/crs_matrix.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

namespace shapesense {
namespace {

Eigen::MatrixXd DenseFromCrs(const ceres::CRSMatrix& crs) {
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[static_cast<size_t>(row)]; k < crs.rows[static_cast<size_t>(row) + 1];
         ++k) {
      dense(row, crs.cols[static_cast<size_t>(k)]) = crs.values[static_cast<size_t>(k)];
    }
  }
  return dense;
}

}  // namespace

Eigen::MatrixXd InverseGaussNewtonHessian(ceres::Problem& problem,
                                          const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  ceres::CRSMatrix jacobian;
  problem.Evaluate(options, nullptr, nullptr, nullptr, &jacobian);
  const Eigen::MatrixXd j = DenseFromCrs(jacobian);
  const Eigen::MatrixXd hessian = j.transpose() * j;
  // Scaled to a unit diagonal first, so that parameters of different units
  // (1/mm against mm) do not pass for unconstrained ones.
  const Eigen::VectorXd scale = hessian.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * hessian * scale.asDiagonal();
  // Eigen-decomposition rather than a Cholesky factor so that an unconstrained
  // direction shows up as an infinite variance instead of a garbage number.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const Eigen::MatrixXd& vectors = eigen.eigenvectors();
  const int size = static_cast<int>(values.size());
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(size, size);
  std::vector<int> unconstrained;
  for (int k = 0; k < size; ++k) {
    if (values(k) > 1e-12 * size) {
      covariance += vectors.col(k) * vectors.col(k).transpose() / values(k);
    } else {
      unconstrained.push_back(k);
    }
  }
  covariance = scale.asDiagonal() * covariance * scale.asDiagonal();
  for (const int k : unconstrained) {
    for (int r = 0; r < size; ++r) {
      if (std::abs(vectors(r, k)) > 1e-6 || hessian(r, r) == 0.0) {
        covariance(r, r) = std::numeric_limits<double>::infinity();
      }
    }
  }
  return covariance;
}

}  // namespace shapesense
