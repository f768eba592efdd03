#include "libs/calibration/point_registration.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libs/core/error.h"

namespace shapesense {
namespace {

Vec3 Centroid(const std::vector<Vec3>& points) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

void CheckPointSets(const std::vector<Vec3>& from, const std::vector<Vec3>& to) {
  if (from.size() != to.size()) {
    throw InputError("registration: " + std::to_string(from.size()) + " sensed points against " +
                     std::to_string(to.size()) + " reference points; expected pairs");
  }
  if (from.size() < 3) {
    throw InputError("registration: expected at least 3 point pairs, got " +
                     std::to_string(from.size()));
  }
  for (size_t i = 0; i < from.size(); ++i) {
    if (!from[i].allFinite() || !to[i].allFinite()) {
      throw InputError("registration: point " + std::to_string(i + 1) + " is not finite");
    }
  }
}

// Spread of the points about their centroid: singular values, largest first.
Vec3 Spread(const std::vector<Vec3>& points) {
  const Vec3 centre = Centroid(points);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) scatter += (p - centre) * (p - centre).transpose();
  // The scatter is symmetric: its eigenvalues (ascending) are the squared spreads.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter, Eigen::EigenvaluesOnly);
  const Vec3 ascending = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return ascending.reverse();
}

void CheckNotCollinear(const std::vector<Vec3>& points, const std::string& which) {
  const Vec3 spread = Spread(points);
  if (!(spread(1) > 1e-6 * std::max(spread(0), 1e-9)) || spread(0) < 1e-9) {
    throw InputError("registration: the " + which +
                     " points are (nearly) collinear, which leaves the rotation about their line "
                     "free; expected points spread over a plane or a volume");
  }
}

PointRegistration Evaluate(const std::vector<Vec3>& sensed, const std::vector<Vec3>& reference,
                           const Pose3& reference_from_sensed) {
  PointRegistration result;
  result.reference_from_sensed = reference_from_sensed;
  Vec3 sum_squares = Vec3::Zero();
  for (size_t i = 0; i < sensed.size(); ++i) {
    const Vec3 error = reference_from_sensed * sensed[i] - reference[i];
    result.errors.push_back(error);
    sum_squares += error.cwiseAbs2();
    result.max_error = std::max(result.max_error, error.norm());
  }
  const double n = static_cast<double>(sensed.size());
  result.rms_per_axis = (sum_squares / n).cwiseSqrt();
  result.rms = std::sqrt(sum_squares.sum() / n);
  return result;
}

Polyline ToPolyline(const std::vector<Vec3>& points) { return {points.begin(), points.end()}; }

}  // namespace

PointRegistration RegisterPoints(const std::vector<Vec3>& sensed,
                                 const std::vector<Vec3>& reference,
                                 const RegistrationOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("registration options: " + error);
  }
  CheckPointSets(sensed, reference);
  CheckNotCollinear(sensed, "sensed");
  CheckNotCollinear(reference, "reference");
  const Registration fit = RegisterPointSets(ToPolyline(sensed), ToPolyline(reference), options);
  if (!fit.converged) {
    throw InputError("registration: " + fit.message);
  }
  return Evaluate(sensed, reference, fit.target_from_source);
}

}  // namespace shapesense
