#pragma once

// The matrices of the linear tendon model (docs/mechanics.md), templated on
// the scalar so that Ceres can differentiate them with respect to the
// stiffnesses.
//
//   D   (4 x n)  column i = [dz_i, -dx_i, 1, 1]: generalised force per unit tension
//   L0  (4 x 4)  diag(L1, L1, L0, L1): length over which each component of q acts
//   K_m (4 x 4)  diag(K_x, K_z, K_a0, K_a1)
//   C_m (n x n)  D^T L0 K_m^-1 D + L_t K_t^-1: displacement per unit tension
//   A   (4 x n)  K_m^-1 D C_m^-1: configuration per unit displacement

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace shapesense {

template <class T>
using Matrix4X = Eigen::Matrix<T, 4, Eigen::Dynamic>;
template <class T>
using MatrixX = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

// K_m^-1 D.
template <class T>
Matrix4X<T> CompliantMomentArms(const Eigen::Matrix4Xd& moment_arms,
                                const Eigen::Matrix<T, 4, 1>& stiffness) {
  Matrix4X<T> out = moment_arms.cast<T>();
  for (int row = 0; row < 4; ++row) out.row(row) /= stiffness(row);
  return out;
}

// C_m = D^T L0 K_m^-1 D + L_t K_t^-1 (tendon_compliance = L_t / K_t per tendon).
template <class T>
MatrixX<T> DisplacementCompliance(const Eigen::Matrix4Xd& moment_arms,
                                  const Eigen::Vector4d& configuration_lengths,
                                  const Eigen::Matrix<T, 4, 1>& stiffness,
                                  const Eigen::VectorXd& tendon_compliance) {
  const Matrix4X<T> compliant = CompliantMomentArms(moment_arms, stiffness);
  MatrixX<T> weighted_arms = (configuration_lengths.asDiagonal() * moment_arms).cast<T>();
  MatrixX<T> compliance = weighted_arms.transpose() * compliant;
  compliance.diagonal() += tendon_compliance.cast<T>();
  return compliance;
}

// A = K_m^-1 D C_m^-1 (C_m is symmetric positive definite, so A^T = C_m^-1 D^T K_m^-1).
template <class T>
Matrix4X<T> ActuationMatrix(const Eigen::Matrix4Xd& moment_arms,
                            const Eigen::Vector4d& configuration_lengths,
                            const Eigen::Matrix<T, 4, 1>& stiffness,
                            const Eigen::VectorXd& tendon_compliance) {
  const MatrixX<T> compliance =
      DisplacementCompliance(moment_arms, configuration_lengths, stiffness, tendon_compliance);
  const MatrixX<T> compliant_t = CompliantMomentArms(moment_arms, stiffness).transpose();
  return compliance.ldlt().solve(compliant_t).transpose();
}

}  // namespace shapesense
