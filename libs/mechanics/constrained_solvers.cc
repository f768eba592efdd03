#include "libs/mechanics/constrained_solvers.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <bit>
#include <stdexcept>
#include <vector>

namespace shapesense {
namespace {

// z with z_i = 0 outside `basic` and (M z - b)_i = 0 inside it.
Eigen::VectorXd SolveOnBasis(const Eigen::MatrixXd& m, const Eigen::VectorXd& b,
                             const std::vector<bool>& basic) {
  std::vector<int> index;
  for (int i = 0; i < static_cast<int>(basic.size()); ++i) {
    if (basic[static_cast<size_t>(i)]) index.push_back(i);
  }
  Eigen::VectorXd z = Eigen::VectorXd::Zero(b.size());
  if (index.empty()) return z;
  const Eigen::VectorXd sub = Eigen::MatrixXd(m(index, index)).partialPivLu().solve(b(index));
  z(index) = sub;
  return z;
}

// Scales every row to unit norm so that one tolerance fits all constraints.
void NormalizeRows(Eigen::MatrixXd& rows, Eigen::VectorXd& rhs) {
  for (int i = 0; i < rows.rows(); ++i) {
    const double norm = rows.row(i).norm();
    if (norm > 0.0) {
      rows.row(i) /= norm;
      rhs(i) /= norm;
    }
  }
}

struct ActiveSetSolution {
  Eigen::VectorXd x;
  Eigen::VectorXd multipliers;  // of the stacked rows, equalities first
};

// Least-norm x on the affine set {rows x = rhs}: x = rows^T lambda with
// (rows rows^T) lambda = rhs. nullopt when the rows are dependent.
std::optional<ActiveSetSolution> LeastNormOnAffineSet(const Eigen::MatrixXd& rows,
                                                      const Eigen::VectorXd& rhs) {
  if (rows.rows() == 0) return ActiveSetSolution{Eigen::VectorXd::Zero(rows.cols()), {}};
  Eigen::FullPivHouseholderQR<Eigen::MatrixXd> qr(rows.transpose());
  qr.setThreshold(1e-10);
  if (qr.rank() < rows.rows()) return std::nullopt;
  const Eigen::VectorXd lambda = (rows * rows.transpose()).ldlt().solve(rhs);
  return ActiveSetSolution{rows.transpose() * lambda, lambda};
}

}  // namespace

std::optional<Eigen::VectorXd> SolveComplementarity(const Eigen::MatrixXd& m,
                                                    const Eigen::VectorXd& b) {
  const int n = static_cast<int>(b.size());
  const double tolerance = 1e-12 * (1.0 + b.cwiseAbs().maxCoeff());
  std::vector<bool> basic(static_cast<size_t>(n), true);
  const long max_steps = (1L << std::min(n, 24)) + 16;
  for (long step = 0; step < max_steps; ++step) {
    const Eigen::VectorXd z = SolveOnBasis(m, b, basic);
    const Eigen::VectorXd w = m * z - b;
    int violated = -1;
    for (int i = 0; i < n && violated < 0; ++i) {
      const bool in_basis = basic[static_cast<size_t>(i)];
      if ((in_basis && z(i) < -tolerance) || (!in_basis && w(i) < -tolerance)) violated = i;
    }
    if (violated < 0) return z;
    basic[static_cast<size_t>(violated)] = !basic[static_cast<size_t>(violated)];
  }
  return std::nullopt;
}

std::optional<Eigen::VectorXd> LeastNormWithInequalities(const Eigen::MatrixXd& equality,
                                                         const Eigen::VectorXd& equality_rhs,
                                                         const Eigen::MatrixXd& inequality,
                                                         const Eigen::VectorXd& inequality_rhs) {
  const int num_inequalities = static_cast<int>(inequality.rows());
  if (num_inequalities > 20) {
    throw std::invalid_argument("LeastNormWithInequalities: more than 20 inequalities");
  }
  Eigen::MatrixXd e = equality, g = inequality;
  Eigen::VectorXd e_rhs = equality_rhs, g_rhs = inequality_rhs;
  NormalizeRows(e, e_rhs);
  NormalizeRows(g, g_rhs);
  const double tolerance = 1e-9 * (1.0 + e_rhs.cwiseAbs().sum() + g_rhs.cwiseAbs().sum());
  const int max_active = static_cast<int>(e.cols() - e.rows());
  for (unsigned mask = 0; mask < (1u << num_inequalities); ++mask) {
    if (std::popcount(mask) > max_active) continue;
    std::vector<int> active;
    for (int i = 0; i < num_inequalities; ++i) {
      if (mask & (1u << i)) active.push_back(i);
    }
    Eigen::MatrixXd rows(e.rows() + static_cast<int>(active.size()), e.cols());
    Eigen::VectorXd rhs(rows.rows());
    rows << e, g(active, Eigen::all);
    rhs << e_rhs, g_rhs(active);
    const std::optional<ActiveSetSolution> solution = LeastNormOnAffineSet(rows, rhs);
    if (!solution) continue;
    const bool multipliers_nonnegative =
        (solution->multipliers.tail(static_cast<int>(active.size())).array() >= -tolerance).all();
    const bool feasible = ((g * solution->x - g_rhs).array() >= -tolerance).all();
    if (multipliers_nonnegative && feasible) return solution->x;
  }
  return std::nullopt;
}

}  // namespace shapesense
