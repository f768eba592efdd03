#include "libs/mechanics/stiffness_estimation.h"

#include <ceres/ceres.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "libs/mechanics/configuration_geometry.h"
#include "libs/mechanics/dense_covariance.h"
#include "libs/mechanics/tendon_matrices.h"

namespace shapesense {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Poses as columns: displacements (n x N), sensed configurations (4 x N).
struct PoseMatrices {
  Eigen::MatrixXd displacements;
  Eigen::Matrix4Xd configurations;
  Eigen::MatrixXd tensions;
};

std::string CheckPoses(const TendonModel& model, const std::vector<PoseSample>& poses,
                       bool need_tensions) {
  if (poses.size() < 2) return "expected at least 2 poses, got " + std::to_string(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const PoseSample& pose = poses[i];
    const std::string where = "pose " + std::to_string(i) + ": ";
    if (pose.displacements.size() != model.num_tendons()) {
      return where + "expected " + std::to_string(model.num_tendons()) + " displacements";
    }
    if (need_tensions && pose.tensions.size() != model.num_tendons()) {
      return where + "expected " + std::to_string(model.num_tendons()) + " tensions";
    }
    if (!pose.displacements.allFinite() || !pose.configuration.allFinite() ||
        !pose.tensions.allFinite()) {
      return where + "expected finite numbers";
    }
  }
  return "";
}

PoseMatrices Stack(const std::vector<PoseSample>& poses, int num_tendons, bool with_tensions) {
  const int count = static_cast<int>(poses.size());
  PoseMatrices out{Eigen::MatrixXd(num_tendons, count), Eigen::Matrix4Xd(4, count),
                   Eigen::MatrixXd(with_tensions ? num_tendons : 0, count)};
  for (int i = 0; i < count; ++i) {
    const PoseSample& pose = poses[static_cast<size_t>(i)];
    out.displacements.col(i) = pose.displacements;
    out.configurations.col(i) = pose.configuration;
    if (with_tensions) out.tensions.col(i) = pose.tensions;
  }
  return out;
}

std::string Percent(double fraction) {
  std::ostringstream out;
  out.precision(3);
  out << 100.0 * fraction << "%";
  return out.str();
}

// A warning for every stiffness the poses leave poorly identified.
std::vector<std::string> IdentifiabilityWarnings(const StiffnessVector& stiffness,
                                                 const StiffnessVector& std_dev,
                                                 double max_relative_std) {
  std::vector<std::string> warnings;
  for (int j = 0; j < 4; ++j) {
    const std::string name = kStiffnessNames[static_cast<size_t>(j)];
    const double relative = std_dev(j) / std::abs(stiffness(j));
    if (!(relative <= 1.0)) {
      warnings.push_back(name +
                         " is not identified by these poses (they do not exercise it; "
                         "its standard deviation is " +
                         (std::isfinite(relative) ? Percent(relative) : "infinite") +
                         " of the estimate)");
    } else if (relative > max_relative_std) {
      warnings.push_back(name + " is poorly identified by these poses: its standard deviation is " +
                         Percent(relative) + " of the estimate (limit " +
                         Percent(max_relative_std) + ")");
    }
  }
  return warnings;
}

// Slope through the origin of `response` against `regressor`, with its
// standard deviation from the residual variance. Infinite when the regressor
// is all zero.
struct Slope {
  double value = 0.0;
  double std_dev = kInfinity;
};
Slope FitSlope(const Eigen::VectorXd& regressor, const Eigen::VectorXd& response) {
  const double sum_sq = regressor.squaredNorm();
  if (!(sum_sq > 0.0)) return {};
  Slope slope;
  slope.value = regressor.dot(response) / sum_sq;
  const double dof = static_cast<double>(regressor.size() - 1);
  const double variance = (response - slope.value * regressor).squaredNorm() / dof;
  slope.std_dev = std::sqrt(variance / sum_sq);
  return slope;
}

Configuration ResidualRms(const TendonModel& model, const StiffnessVector& stiffness,
                          const PoseMatrices& data) {
  if (!(stiffness.array() > 0.0).all()) return Configuration::Constant(kInfinity);
  const Eigen::Matrix4Xd actuation = ActuationMatrix<double>(
      model.moment_arms(), model.configuration_lengths(), stiffness, model.tendon_compliance());
  const Eigen::Matrix4Xd residual = data.configurations - actuation * data.displacements;
  return (residual.rowwise().squaredNorm() / static_cast<double>(residual.cols())).cwiseSqrt();
}

// Fills validity, residuals and warnings once stiffness and standard
// deviation are set.
void Finish(const TendonModel& model, const PoseMatrices& data, const EstimationOptions& options,
            StiffnessEstimate& estimate) {
  estimate.valid = true;
  for (int j = 0; j < 4 && estimate.valid; ++j) {
    if (!(estimate.stiffness(j) > 0.0) || !std::isfinite(estimate.stiffness(j))) {
      estimate.valid = false;
      std::ostringstream message;
      message << kStiffnessNames[static_cast<size_t>(j)] << " came out non-positive or undefined ("
              << estimate.stiffness(j) << ")";
      estimate.message = message.str();
    }
  }
  estimate.residual_rms = ResidualRms(model, estimate.stiffness, data);
  estimate.warnings = IdentifiabilityWarnings(estimate.stiffness, estimate.standard_deviation,
                                              options.max_relative_std);
}

// q against A(exp(log_k)) y, component j weighted by 1/noise_j.
struct OutputErrorResidual {
  const TendonModel* model;
  const PoseMatrices* data;
  Eigen::Vector4d noise;

  template <class T>
  bool operator()(const T* log_stiffness, T* residual) const {
    using std::exp;
    Eigen::Matrix<T, 4, 1> stiffness;
    for (int j = 0; j < 4; ++j) stiffness(j) = exp(log_stiffness[j]);
    const Matrix4X<T> actuation =
        ActuationMatrix<T>(model->moment_arms(), model->configuration_lengths(), stiffness,
                           model->tendon_compliance());
    const Matrix4X<T> predicted = actuation * data->displacements.cast<T>();
    for (int i = 0; i < predicted.cols(); ++i) {
      for (int j = 0; j < 4; ++j) {
        residual[4 * i + j] = (T(data->configurations(j, i)) - predicted(j, i)) / noise(j);
      }
    }
    return true;
  }
};

struct OutputErrorFit {
  Eigen::Vector4d log_stiffness;
  Eigen::Matrix4d covariance;  // of the log-stiffnesses
  ceres::Solver::Summary summary;
};

OutputErrorFit FitOutputError(const TendonModel& model, const PoseMatrices& data,
                              const Eigen::Vector4d& noise, const Eigen::Vector4d& start,
                              int max_iterations) {
  OutputErrorFit fit;
  fit.log_stiffness = start;
  ceres::Problem problem;
  const int num_residuals = 4 * static_cast<int>(data.configurations.cols());
  auto* cost = new ceres::AutoDiffCostFunction<OutputErrorResidual, ceres::DYNAMIC, 4>(
      new OutputErrorResidual{&model, &data, noise}, num_residuals);
  problem.AddResidualBlock(cost, nullptr, fit.log_stiffness.data());
  // Keeps an unidentified stiffness from wandering off to 0 or infinity.
  for (int j = 0; j < 4; ++j) {
    problem.SetParameterLowerBound(fit.log_stiffness.data(), j, start(j) - std::log(1e4));
    problem.SetParameterUpperBound(fit.log_stiffness.data(), j, start(j) + std::log(1e4));
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = max_iterations;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  ceres::Solve(options, &problem, &fit.summary);
  const double dof = num_residuals - 4;
  const double variance = dof > 0 ? 2.0 * fit.summary.final_cost / dof : kInfinity;
  fit.covariance = variance * InverseGaussNewtonHessian(problem, {fit.log_stiffness.data()});
  return fit;
}

// Per-component noise levels from the residuals of a fit, floored so that
// exact data do not divide by zero.
Eigen::Vector4d NoiseFromResiduals(const TendonModel& model, const PoseMatrices& data,
                                   const Eigen::Vector4d& log_stiffness) {
  const Eigen::Vector4d rms = ResidualRms(model, log_stiffness.array().exp(), data);
  const double count = static_cast<double>(data.configurations.cols());
  const Eigen::Vector4d scale = (data.configurations.rowwise().squaredNorm() / count).cwiseSqrt();
  Eigen::Vector4d noise = rms * std::sqrt(count / std::max(count - 1.0, 1.0));
  return noise.cwiseMax(1e-9 * scale).cwiseMax(1e-15);
}

}  // namespace

std::string EstimationOptions::Validate() const {
  if (!(curvature_noise > 0.0)) return "curvature_noise: expected a positive number";
  if (!(strain_noise > 0.0)) return "strain_noise: expected a positive number";
  if (!(max_relative_std > 0.0)) return "max_relative_std: expected a positive number";
  if (max_iterations <= 0) return "max_iterations: expected a positive integer";
  return "";
}

StiffnessEstimate EstimateStiffnessTensionless(const TendonModel& model,
                                               const std::vector<PoseSample>& poses,
                                               const EstimationOptions& options) {
  StiffnessEstimate estimate;
  estimate.method = "tensionless";
  estimate.message = CheckPoses(model, poses, false);
  if (!estimate.message.empty()) return estimate;
  const PoseMatrices data = Stack(poses, model.num_tendons(), false);
  // Right side D K_t L_t^-1 (y - D^T L0 q): the force the stretched tendons apply.
  const Eigen::MatrixXd stretch =
      data.displacements - model.moment_arms().transpose() *
                               model.configuration_lengths().asDiagonal() * data.configurations;
  const Eigen::Matrix4Xd force =
      model.moment_arms() * model.tendon_compliance().cwiseInverse().asDiagonal() * stretch;
  for (int j = 0; j < 4; ++j) {
    const Slope slope = FitSlope(data.configurations.row(j).transpose(), force.row(j).transpose());
    estimate.stiffness(j) = slope.value;
    estimate.standard_deviation(j) = slope.std_dev;
  }
  Finish(model, data, options, estimate);
  return estimate;
}

StiffnessEstimate EstimateStiffnessFromTensions(const TendonModel& model,
                                                const std::vector<PoseSample>& poses,
                                                const EstimationOptions& options) {
  StiffnessEstimate estimate;
  estimate.method = "tensions";
  estimate.message = CheckPoses(model, poses, true);
  if (!estimate.message.empty()) return estimate;
  const PoseMatrices data = Stack(poses, model.num_tendons(), true);
  const Eigen::Matrix4Xd force = model.moment_arms() * data.tensions;
  for (int j = 0; j < 4; ++j) {
    // Compliance c_j = 1 / K_j, with q_j as the response.
    const Slope compliance =
        FitSlope(force.row(j).transpose(), data.configurations.row(j).transpose());
    estimate.stiffness(j) = 1.0 / compliance.value;
    estimate.standard_deviation(j) = compliance.std_dev / (compliance.value * compliance.value);
  }
  Finish(model, data, options, estimate);
  return estimate;
}

StiffnessEstimate EstimateStiffnessOutputError(const TendonModel& model,
                                               const std::vector<PoseSample>& poses,
                                               const EstimationOptions& options) {
  StiffnessEstimate estimate;
  estimate.method = "output_error";
  estimate.message = CheckPoses(model, poses, false);
  if (estimate.message.empty()) estimate.message = options.Validate();
  if (!estimate.message.empty()) return estimate;
  const PoseMatrices data = Stack(poses, model.num_tendons(), false);
  Eigen::Vector4d noise(options.curvature_noise, options.curvature_noise, options.strain_noise,
                        options.strain_noise);
  const Eigen::Vector4d start = model.stiffness().array().log();
  OutputErrorFit fit = FitOutputError(model, data, noise, start, options.max_iterations);
  if (options.reweight_from_residuals) {
    noise = NoiseFromResiduals(model, data, fit.log_stiffness);
    fit = FitOutputError(model, data, noise, fit.log_stiffness, options.max_iterations);
  }
  estimate.message = fit.summary.message;
  estimate.stiffness = fit.log_stiffness.array().exp();
  // Delta method: std(K) = K std(log K).
  estimate.standard_deviation =
      estimate.stiffness.cwiseProduct(fit.covariance.diagonal().cwiseSqrt());
  Finish(model, data, options, estimate);
  if (!fit.summary.IsSolutionUsable()) estimate.valid = false;
  return estimate;
}

TipErrors ComputeTipErrors(const TendonModel& model, const std::vector<PoseSample>& poses) {
  TipErrors errors;
  const SectionLengths rest = model.lengths();
  for (const PoseSample& pose : poses) {
    const Vec3 sensed = BaseFromTip(pose.configuration, rest).translation();
    const Vec3 predicted = BaseFromTip(model.Forward(pose.displacements), rest).translation();
    errors.percent.push_back(100.0 * (predicted - sensed).norm() / rest.distal);
  }
  if (errors.percent.empty()) return errors;
  const Eigen::Map<const Eigen::VectorXd> values(errors.percent.data(),
                                                 static_cast<int>(errors.percent.size()));
  errors.mean = values.mean();
  errors.max = values.maxCoeff();
  if (values.size() > 1) {
    errors.std = std::sqrt((values.array() - errors.mean).square().sum() / (values.size() - 1.0));
  }
  return errors;
}

}  // namespace shapesense
