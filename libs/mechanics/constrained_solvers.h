#pragma once

// Small dense solvers for the tendon model's one-sided constraints (tendons
// pull, never push). Sizes are a handful of tendons, so both favour being
// exact and simple over scaling.

#include <Eigen/Core>
#include <optional>

namespace shapesense {

// Linear complementarity: z >= 0 with w = M z - b >= 0 and z_i w_i = 0 for
// every i. For a P-matrix M (every symmetric positive definite matrix is one)
// the solution exists and is unique, and Murty's least-index principal
// pivoting reaches it in finitely many steps. nullopt when the step limit
// runs out, which a P-matrix never causes.
std::optional<Eigen::VectorXd> SolveComplementarity(const Eigen::MatrixXd& m,
                                                    const Eigen::VectorXd& b);

// The least-norm x with E x = e and G x >= h, or nullopt when no x satisfies
// them. Exact: it finds the active set whose equality-constrained solution
// meets the KKT conditions (primal feasible, multipliers >= 0), unique since
// the objective is strictly convex. Tries at most 2^G.rows() active sets, so
// it refuses (std::invalid_argument) more than 20 inequalities.
std::optional<Eigen::VectorXd> LeastNormWithInequalities(const Eigen::MatrixXd& equality,
                                                         const Eigen::VectorXd& equality_rhs,
                                                         const Eigen::MatrixXd& inequality,
                                                         const Eigen::VectorXd& inequality_rhs);

}  // namespace shapesense
