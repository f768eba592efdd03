#include "libs/registration/rigid_registration.h"

#include <ceres/ceres.h>

#include <Eigen/SVD>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

struct PairResidual {
  Vec3 source;
  Vec3 target;

  template <class T>
  bool operator()(const T* rotation, const T* translation, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(rotation);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(translation);
    const Eigen::Matrix<T, 3, 1> moved = q * source.cast<T>() + t;
    for (int k = 0; k < 3; ++k) residual[k] = moved(k) - T(target(k));
    return true;
  }
};

Vec3 Centroid(const Polyline& points) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

// Singular values of the centred source points' scatter: the second is ~0
// when they lie on a line.
Vec3 SpreadOf(const Polyline& points) {
  const Vec3 centre = Centroid(points);
  Mat3 scatter = Mat3::Zero();
  for (const Vec3& p : points) scatter += (p - centre) * (p - centre).transpose();
  return Eigen::JacobiSVD<Mat3>(scatter).singularValues();
}

std::string CheckPairs(const Polyline& source, const Polyline& target) {
  if (source.size() != target.size()) return "registration: the point sets differ in size";
  if (source.size() < 3) return "registration: expected at least 3 pairs";
  for (size_t i = 0; i < source.size(); ++i) {
    if (!source[i].allFinite() || !target[i].allFinite())
      return "registration: expected finite points";
  }
  const Vec3 spread = SpreadOf(source);
  if (!(spread(1) > 1e-12 * spread(0))) {
    return "registration: the points lie on one line, so the rotation about it is undetermined";
  }
  return "";
}

void MeasureResiduals(const Polyline& source, const Polyline& target, Registration& result) {
  Vec3 sum_sq = Vec3::Zero();
  for (size_t i = 0; i < source.size(); ++i) {
    sum_sq += (result.target_from_source * source[i] - target[i]).cwiseAbs2();
  }
  const double count = static_cast<double>(source.size());
  result.rms_per_axis = (sum_sq / count).cwiseSqrt();
  result.rms = std::sqrt(sum_sq.sum() / count);
}

// Points at `count` equal fractions of the curve's length, ends included.
Polyline SampleByFraction(const Polyline& curve, int count) {
  const std::vector<double> arc = CumulativeArcLength(curve);
  Polyline out;
  for (int k = 0; k < count; ++k) {
    out.push_back(PointAtArcLength(curve, arc, arc.back() * k / (count - 1)));
  }
  return out;
}

}  // namespace

std::string RegistrationOptions::Validate() const {
  if (!(loss_scale >= 0.0)) return "loss_scale: expected a number >= 0";
  if (max_iterations <= 0) return "max_iterations: expected a positive integer";
  return "";
}

Pose3 AlignClosedForm(const Polyline& source, const Polyline& target) {
  const Vec3 source_centre = Centroid(source), target_centre = Centroid(target);
  Mat3 cross = Mat3::Zero();
  for (size_t i = 0; i < source.size(); ++i) {
    cross += (target[i] - target_centre) * (source[i] - source_centre).transpose();
  }
  const Eigen::JacobiSVD<Mat3> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // A reflection would fit better when the data are degenerate or very
  // noisy; flipping the weakest axis keeps a proper rotation.
  Mat3 flip = Mat3::Identity();
  flip(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  Pose3 pose = Pose3::Identity();
  pose.linear() = svd.matrixU() * flip * svd.matrixV().transpose();
  pose.translation() = target_centre - pose.linear() * source_centre;
  return pose;
}

Registration RegisterPointSets(const Polyline& source, const Polyline& target,
                               const RegistrationOptions& options) {
  Registration result;
  result.message = CheckPairs(source, target);
  if (result.message.empty()) result.message = options.Validate();
  if (!result.message.empty()) return result;
  const Pose3 start = AlignClosedForm(source, target);
  Eigen::Quaterniond rotation(start.linear());
  Vec3 translation = start.translation();
  ceres::Problem problem;
  for (size_t i = 0; i < source.size(); ++i) {
    ceres::LossFunction* loss =
        options.loss_scale > 0.0 ? new ceres::HuberLoss(options.loss_scale) : nullptr;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PairResidual, 3, 4, 3>(
                                 new PairResidual{source[i], target[i]}),
                             loss, rotation.coeffs().data(), translation.data());
  }
  problem.SetManifold(rotation.coeffs().data(), new ceres::EigenQuaternionManifold());
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  result.converged = summary.IsSolutionUsable();
  result.message = summary.message;
  result.target_from_source.linear() = rotation.normalized().toRotationMatrix();
  result.target_from_source.translation() = translation;
  MeasureResiduals(source, target, result);
  return result;
}

Registration RegisterCurves(const std::vector<Polyline>& source_curves,
                            const std::vector<Polyline>& target_curves, int samples_per_curve,
                            const RegistrationOptions& options) {
  Registration result;
  if (source_curves.size() != target_curves.size() || source_curves.empty()) {
    result.message = "registration: expected the same number of source and target curves";
    return result;
  }
  if (samples_per_curve < 2) {
    result.message = "registration: expected at least 2 samples per curve";
    return result;
  }
  Polyline source, target;
  for (size_t c = 0; c < source_curves.size(); ++c) {
    if (source_curves[c].size() < 2 || target_curves[c].size() < 2) {
      result.message = "registration: curve " + std::to_string(c) + " has fewer than 2 points";
      return result;
    }
    const Polyline s = SampleByFraction(source_curves[c], samples_per_curve);
    const Polyline t = SampleByFraction(target_curves[c], samples_per_curve);
    source.insert(source.end(), s.begin(), s.end());
    target.insert(target.end(), t.begin(), t.end());
  }
  return RegisterPointSets(source, target, options);
}

}  // namespace shapesense
