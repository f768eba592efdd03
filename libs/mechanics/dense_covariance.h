#pragma once

// Covariance of a Ceres fit's parameters from its Jacobian, densely (the
// problems here have at most a few hundred parameters). Internal to the
// fitting code of libs/mechanics.

#include <ceres/problem.h>

#include <Eigen/Core>
#include <vector>

namespace shapesense {

// (J^T J)^-1 over the tangent spaces of `blocks`, in their order, J being the
// Jacobian of the (robustified) residuals at the current parameter values.
// Directions the data do not constrain get an infinite variance.
Eigen::MatrixXd InverseGaussNewtonHessian(ceres::Problem& problem,
                                          const std::vector<double*>& blocks);

}  // namespace shapesense
