#include "libs/mechanics/arc_fit.h"

#include <ceres/ceres.h>

#include <cmath>

#include "libs/geometry/polyline.h"
#include "libs/mechanics/arc_geometry.h"
#include "libs/mechanics/dense_covariance.h"

namespace shapesense {
namespace {

// A sensed point against the arc, in the frame of the arc's start.
struct ArcPointResidual {
  Vec3 observed;

  template <class T>
  bool operator()(const T* curvature, const T* s, T* residual) const {
    const Eigen::Matrix<T, 3, 1> model = ArcPoint(curvature[0], curvature[1], s[0]);
    for (int k = 0; k < 3; ++k) residual[k] = model(k) - observed(k);
    return true;
  }
};

// v turned by the least rotation that takes unit vector `from` to unit `to`
// (Rodrigues with w = from x to, c = from . to; fine away from c = -1).
template <class T>
Eigen::Matrix<T, 3, 1> TurnLeast(const Eigen::Matrix<T, 3, 1>& from,
                                 const Eigen::Matrix<T, 3, 1>& to,
                                 const Eigen::Matrix<T, 3, 1>& v) {
  const Eigen::Matrix<T, 3, 1> w = from.cross(to);
  const T c = from.dot(to);
  return v + w.cross(v) + w.cross(w.cross(v)) / (T(1.0) + c);
}

// A sensed point (world frame) against the arc hung from an estimated base:
// world = position + Turn(initial axis -> axis) R0 (proximal * y + arc(s)).
struct ArcPointWithBaseResidual {
  Vec3 observed;
  Mat3 initial_rotation;  // world_from_base of the initial guess
  double proximal_length;

  template <class T>
  bool operator()(const T* curvature, const T* s, const T* position, const T* axis,
                  T* residual) const {
    Eigen::Matrix<T, 3, 1> in_base = ArcPoint(curvature[0], curvature[1], s[0]);
    in_base.y() += T(proximal_length);
    const Eigen::Matrix<T, 3, 1> rotated = initial_rotation.cast<T>() * in_base;
    const Eigen::Matrix<T, 3, 1> initial_axis = initial_rotation.col(1).cast<T>();
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> axis_now(axis);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> origin(position);
    const Eigen::Matrix<T, 3, 1> model = origin + TurnLeast<T>(initial_axis, axis_now, rotated);
    for (int k = 0; k < 3; ++k) residual[k] = model(k) - observed(k);
    return true;
  }
};

std::string CheckInput(const ArcFitInput& input) {
  if (input.points.size() < 3) return "arc fit: expected at least 3 points";
  if (!(input.rest.proximal > 0.0) || !(input.rest.distal > 0.0)) {
    return "arc fit: expected positive rest lengths";
  }
  for (const Vec3& point : input.points) {
    if (!point.allFinite()) return "arc fit: expected finite points";
  }
  return "";
}

// Curvature of the arc through the start and the tip, both in the start's
// frame: exact for an exact arc, a fine start for a noisy one.
Eigen::Vector2d CurvatureThroughTip(const Vec3& tip, double length) {
  const double lateral = std::hypot(tip.x(), tip.z());
  if (lateral < 1e-12) return Eigen::Vector2d::Zero();
  const double curvature = 2.0 * std::atan2(lateral, tip.y()) / length;
  return {curvature * tip.z() / lateral, -curvature * tip.x() / lateral};
}

struct FitState {
  Eigen::Vector2d curvature = Eigen::Vector2d::Zero();
  std::vector<double> arc_lengths;
  Vec3 base_position = Vec3::Zero();
  Vec3 base_axis = Vec3::UnitY();
};

struct Setup {
  Pose3 world_from_start;  // fixed frame of the arc's start (base-frame mode)
  double distal_length = 0.0;
  double proximal_length = 0.0;
};

Setup MakeSetup(const ArcFitInput& input) {
  Setup setup;
  setup.distal_length =
      input.distal_length > 0.0 ? input.distal_length : PolylineLength(input.points);
  setup.proximal_length = input.proximal_length > 0.0 ? input.proximal_length : input.rest.proximal;
  setup.world_from_start =
      input.world_from_base * Eigen::Translation3d(0.0, setup.proximal_length, 0.0);
  return setup;
}

FitState InitialState(const ArcFitInput& input, const Setup& setup) {
  FitState state;
  const Vec3 tip_in_start = setup.world_from_start.inverse() * input.points.back();
  state.curvature = CurvatureThroughTip(tip_in_start, setup.distal_length);
  const std::vector<double> arc = CumulativeArcLength(input.points);
  for (const double a : arc) state.arc_lengths.push_back(setup.distal_length * a / arc.back());
  state.arc_lengths.front() = 0.0;
  state.arc_lengths.back() = setup.distal_length;
  state.base_position = input.world_from_base.translation();
  state.base_axis = input.world_from_base.linear().col(1).normalized();
  return state;
}

void AddResiduals(const ArcFitInput& input, const Setup& setup, const ArcFitOptions& options,
                  FitState& state, ceres::Problem& problem) {
  const Pose3 start_from_world = setup.world_from_start.inverse();
  for (size_t i = 0; i < input.points.size(); ++i) {
    ceres::LossFunction* loss =
        options.loss_scale > 0.0 ? new ceres::HuberLoss(options.loss_scale) : nullptr;
    double* s = &state.arc_lengths[i];
    if (options.estimate_base_pose) {
      auto* cost = new ceres::AutoDiffCostFunction<ArcPointWithBaseResidual, 3, 2, 1, 3, 3>(
          new ArcPointWithBaseResidual{input.points[i], input.world_from_base.linear(),
                                       setup.proximal_length});
      problem.AddResidualBlock(cost, loss, state.curvature.data(), s, state.base_position.data(),
                               state.base_axis.data());
    } else {
      auto* cost = new ceres::AutoDiffCostFunction<ArcPointResidual, 3, 2, 1>(
          new ArcPointResidual{start_from_world * input.points[i]});
      problem.AddResidualBlock(cost, loss, state.curvature.data(), s);
    }
    problem.SetParameterLowerBound(s, 0, 0.0);
    problem.SetParameterUpperBound(s, 0, setup.distal_length);
  }
  // The ends of the sensed section are the ends of the arc.
  problem.SetParameterBlockConstant(&state.arc_lengths.front());
  problem.SetParameterBlockConstant(&state.arc_lengths.back());
  if (options.estimate_base_pose) {
    problem.SetManifold(state.base_axis.data(), new ceres::SphereManifold<3>());
  }
}

std::vector<double*> FreeBlocks(FitState& state, bool with_base) {
  std::vector<double*> blocks = {state.curvature.data()};
  for (size_t i = 1; i + 1 < state.arc_lengths.size(); ++i) blocks.push_back(&state.arc_lengths[i]);
  if (with_base) {
    blocks.push_back(state.base_position.data());
    blocks.push_back(state.base_axis.data());
  }
  return blocks;
}

// Covariance of (kappa_x, kappa_z), scaled by the residual variance.
Eigen::Matrix2d CurvatureCovariance(ceres::Problem& problem, FitState& state, bool with_base,
                                    double final_cost, int num_residuals) {
  const std::vector<double*> blocks = FreeBlocks(state, with_base);
  const Eigen::MatrixXd inverse_hessian = InverseGaussNewtonHessian(problem, blocks);
  const int dof = num_residuals - static_cast<int>(inverse_hessian.rows());
  const double variance = dof > 0 ? 2.0 * final_cost / dof : 0.0;
  return variance * inverse_hessian.topLeftCorner<2, 2>();
}

double RmsResidual(const ArcFitInput& input, const Setup& setup, const FitState& state,
                   const Pose3& world_from_base) {
  const Pose3 world_from_start =
      world_from_base * Eigen::Translation3d(0.0, setup.proximal_length, 0.0);
  double sum_sq = 0.0;
  for (size_t i = 0; i < input.points.size(); ++i) {
    const Vec3 model =
        world_from_start * ArcPoint(state.curvature(0), state.curvature(1), state.arc_lengths[i]);
    sum_sq += (model - input.points[i]).squaredNorm();
  }
  return std::sqrt(sum_sq / static_cast<double>(input.points.size()));
}

Pose3 EstimatedWorldFromBase(const ArcFitInput& input, const FitState& state) {
  const Mat3 initial = input.world_from_base.linear();
  Mat3 rotation;
  for (int c = 0; c < 3; ++c) {
    rotation.col(c) = TurnLeast<double>(initial.col(1), state.base_axis, initial.col(c));
  }
  Pose3 pose = Pose3::Identity();
  pose.linear() = rotation;
  pose.translation() = state.base_position;
  return pose;
}

void FillConfiguration(const ArcFitInput& input, const Setup& setup, const FitState& state,
                       ArcFit& fit) {
  fit.configuration << state.curvature(0), state.curvature(1),
      1.0 - setup.proximal_length / input.rest.proximal,
      1.0 - setup.distal_length / input.rest.distal;
  fit.curvature = state.curvature.norm();
  fit.bend_direction = std::atan2(state.curvature(0), -state.curvature(1));
  fit.covariance(2, 2) = std::pow(input.proximal_length_std / input.rest.proximal, 2);
  fit.covariance(3, 3) = std::pow(input.distal_length_std / input.rest.distal, 2);
}

}  // namespace

std::string ArcFitOptions::Validate() const {
  if (!(loss_scale >= 0.0))
    return "loss_scale: expected a number >= 0, got " + std::to_string(loss_scale);
  if (max_iterations <= 0)
    return "max_iterations: expected a positive integer, got " + std::to_string(max_iterations);
  return "";
}

ArcFit FitCircularArc(const ArcFitInput& input, const ArcFitOptions& options) {
  ArcFit fit;
  fit.world_from_base = input.world_from_base;
  fit.message = CheckInput(input);
  if (fit.message.empty()) fit.message = options.Validate();
  if (!fit.message.empty()) return fit;
  const Setup setup = MakeSetup(input);
  FitState state = InitialState(input, setup);
  ceres::Problem problem;
  AddResiduals(input, setup, options, state, problem);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-12;
  solver_options.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  fit.converged = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  fit.message = summary.message;
  if (options.estimate_base_pose) fit.world_from_base = EstimatedWorldFromBase(input, state);
  FillConfiguration(input, setup, state, fit);
  fit.covariance.topLeftCorner<2, 2>() = CurvatureCovariance(
      problem, state, options.estimate_base_pose, summary.final_cost, problem.NumResiduals());
  fit.rms_residual = RmsResidual(input, setup, state, fit.world_from_base);
  return fit;
}

}  // namespace shapesense
