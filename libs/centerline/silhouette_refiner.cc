#include "libs/centerline/silhouette_refiner.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "libs/centerline/silhouette_edges.h"

namespace shapesense {
namespace {

// An edge whose residual exceeds this (and kOutlierFactor times the RMS of
// the others' residuals) is dropped as an outlier, mm.
constexpr double kOutlierMm = 0.3;
constexpr double kOutlierFactor = 4.0;
// Largest move of the tip along the axis that one camera may ask for, mm
// (the end from the voxels is within a voxel or two), and how closely the
// cameras must agree on it.
constexpr double kMaxTipShiftMm = 4.0;
constexpr double kTipAgreementMm = 0.5;
// An outline whose half-width differs from the projected radius by more
// than this fraction (and a pixel) is not this cross-section's alone.
constexpr double kWidthTolerance = 0.3;
// Below this |ray × t| (the sine between an edge's viewing ray and the axis)
// a camera sees the axis too nearly end-on for its edge to place it.
constexpr double kMinSine = 0.25;
// The smallest eigenvalue of the normal matrix that fixes the point.
constexpr double kMinEigenvalue = 0.05;
// Longest walk of an edge search, px: keeps the search cheap.
constexpr int kMaxWalk = 60;

// Two unit vectors spanning the plane normal to the unit vector t.
void NormalBasis(const Vec3& t, Vec3* b1, Vec3* b2) {
  const Vec3 helper = std::abs(t.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  *b1 = t.cross(helper).normalized();
  *b2 = t.cross(*b1);
}

// The linear system of one axis point: row i · x = rhs_i for the active
// edges, x = (displacement along b1, along b2, radius when unknown).
class EdgeSystem {
 public:
  static constexpr size_t kMaxEdges = 64;

  EdgeSystem(const std::vector<EdgeConstraint>& edges, const Vec3& b1, const Vec3& b2,
             double radius, bool estimate_radius)
      : size_(std::min(edges.size(), kMaxEdges)), estimate_radius_(estimate_radius) {
    for (size_t i = 0; i < size_; ++i) {
      rows_[i] = {edges[i].normal.dot(b1), edges[i].normal.dot(b2), estimate_radius ? -1.0 : 0.0};
      rhs_[i] = (estimate_radius ? 0.0 : radius) - edges[i].distance;
      active_[i] = true;
    }
    active_count_ = static_cast<int>(size_);
  }

  struct Solution {
    bool ok = false;
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    double sum_sq = 0.0;  // of the active residuals
    double worst = 0.0;
    size_t worst_index = 0;
  };

  // Least squares over the active rows, leaving out `skip` too.
  Solution Solve(size_t skip = kMaxEdges) const {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d right = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < size_; ++i) {
      if (!active_[i] || i == skip) continue;
      normal += rows_[i] * rows_[i].transpose();
      right += rows_[i] * rhs_[i];
    }
    // Without the radius as an unknown the third column is 0; a unit
    // diagonal keeps x[2] = 0.
    if (!estimate_radius_) normal(2, 2) = 1.0;
    Solution solution;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(normal, Eigen::EigenvaluesOnly);
    if (eigen.eigenvalues().minCoeff() < kMinEigenvalue) return solution;
    solution.x = normal.ldlt().solve(right);
    solution.ok = true;
    for (size_t i = 0; i < size_; ++i) {
      if (!active_[i] || i == skip) continue;
      const double residual = std::abs(rows_[i].dot(solution.x) - rhs_[i]);
      solution.sum_sq += residual * residual;
      if (residual > solution.worst) {
        solution.worst = residual;
        solution.worst_index = i;
      }
    }
    return solution;
  }

  // The edge without which the others agree best, its residual against
  // their solution, and that solution. A far-off edge pulls a fit that
  // includes it towards itself, so the largest residual need not be its.
  struct Suspect {
    size_t index = 0;
    double residual = 0.0;
    Solution others;
  };
  Suspect MostInconsistent() const {
    Suspect suspect;
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < size_; ++i) {
      if (!active_[i]) continue;
      const Solution without = Solve(i);
      if (without.ok && without.sum_sq < best) {
        best = without.sum_sq;
        suspect = {i, std::abs(rows_[i].dot(without.x) - rhs_[i]), without};
      }
    }
    return suspect;
  }

  void Drop(size_t i) {
    active_[i] = false;
    --active_count_;
  }

  int active_count() const { return active_count_; }

 private:
  size_t size_;
  bool estimate_radius_;
  std::array<Eigen::Vector3d, kMaxEdges> rows_;
  std::array<double, kMaxEdges> rhs_{};
  std::array<bool, kMaxEdges> active_{};
  int active_count_ = 0;
};

// Where the ray (from `center`, unit `ray`) passes closest to the axis near
// parameter u: one Gauss-Newton step on the squared distance from the axis
// line at u, then the distance from the curve itself there. The step is
// bounded by a few radii: a grazing ray meets the tube within about
// radius / tan(angle to the axis) of the walk's cross-section.
std::optional<EdgeConstraint> ClosestApproach(const SmoothingSpline& axis, double u, double begin,
                                              double end, const Vec3& center, const Vec3& ray,
                                              double radius) {
  const Vec3 p = axis.Point(u);
  const Vec3 derivative = axis.Derivative(u);
  const Vec3 offset = p - center;
  const Vec3 offset_across = offset - offset.dot(ray) * ray;
  const Vec3 derivative_across = derivative - derivative.dot(ray) * ray;
  const double step = -offset_across.dot(derivative_across) / derivative_across.squaredNorm();
  const double limit = 4.0 * radius / derivative.norm();
  const double closest = std::clamp(u + std::clamp(step, -limit, limit), begin, end);
  const Vec3 there = axis.Point(closest) - center;
  const Vec3 across = there - there.dot(ray) * ray;
  const double distance = across.norm();
  if (!(distance > 1e-9)) return std::nullopt;
  return EdgeConstraint{across / distance, distance};
}

}  // namespace

SilhouetteRefiner::SilhouetteRefiner(const Rig& rig, const std::vector<Silhouette>& silhouettes) {
  for (size_t k = 0; k < rig.cameras.size() && k < silhouettes.size(); ++k) {
    const Camera& camera = rig.cameras[k];
    views_.push_back({&camera, &silhouettes[k], camera.Center(), camera.camera_matrix(0, 0)});
  }
}

bool SilhouetteRefiner::ViewAxis(const View& view, const Vec3& p, const Vec3& t,
                                 AxisView* out) const {
  const Camera& camera = *view.camera;
  const Vec3 cam = camera.cam_from_world * p;
  if (cam.z() <= 1e-6) return false;
  out->normalized = cam.head<2>() / cam.z();
  out->pixel = camera.DistortAndScale(out->normalized);
  // Forward differences: over 1e-4 (a tenth of a pixel) the distortion is
  // linear to far below 1e-3 px.
  constexpr double kStep = 1e-4;
  Eigen::Matrix2d jacobian;
  for (int axis = 0; axis < 2; ++axis) {
    jacobian.col(axis) =
        (camera.DistortAndScale(out->normalized + kStep * Vec2::Unit(axis)) - out->pixel) / kStep;
  }
  out->pixel_to_normalized = jacobian.inverse();
  // The image direction of t: d(normalized)/dt pushed through the Jacobian.
  const Vec3 dcam = camera.cam_from_world.linear() * t;
  const Vec2 dnormalized = (dcam.head<2>() - out->normalized * dcam.z()) / cam.z();
  const Vec2 along = jacobian * dnormalized;
  // Under ~0.2 px per mm the axis points nearly at the camera.
  if (along.norm() < 0.2) return false;
  out->along = along.normalized();
  return true;
}

Vec3 SilhouetteRefiner::RayThrough(const View& view, const AxisView& axis,
                                   const Vec2& pixel) const {
  const Vec2 n = axis.normalized + axis.pixel_to_normalized * (pixel - axis.pixel);
  return (view.camera->cam_from_world.linear().transpose() * Vec3(n.x(), n.y(), 1.0)).normalized();
}

double SilhouetteRefiner::RadiusPx(const View& view, const Vec3& p, double radius) const {
  const double depth = (view.camera->cam_from_world * p).z();
  return view.focal_px * radius / std::max(depth, 1.0);
}

int SilhouetteRefiner::MaxSteps(double radius_px, double extra_px) {
  return std::clamp(static_cast<int>(std::ceil(2.0 * radius_px + extra_px)), 4, kMaxWalk);
}

void SilhouetteRefiner::FindEdges(const SmoothingSpline& axis, double u, double begin, double end,
                                  double radius, double max_offset,
                                  std::vector<EdgeConstraint>* edges) const {
  edges->clear();
  const Vec3 p = axis.Point(u);
  const Vec3 t = axis.Derivative(u).normalized();
  for (const View& view : views_) {
    AxisView seen;
    if (!ViewAxis(view, p, t, &seen)) continue;
    const Vec2 across(-seen.along.y(), seen.along.x());
    const double radius_px = RadiusPx(view, p, radius);
    const int max_steps = MaxSteps(radius_px, 4.0);
    std::array<std::optional<double>, 2> distance;
    for (size_t side = 0; side < 2; ++side) {
      distance[side] =
          FindEdgeAlong(*view.silhouette, seen.pixel, (side == 0 ? 1.0 : -1.0) * across, max_steps);
    }
    // Where another part of the tube overlaps this one in the image the
    // outline is too wide, and neither of its edges belongs to this section.
    if (distance[0] && distance[1] &&
        std::abs(0.5 * (*distance[0] + *distance[1]) - radius_px) >
            kWidthTolerance * radius_px + 1.0) {
      continue;
    }
    for (size_t side = 0; side < 2; ++side) {
      if (!distance[side]) continue;
      const Vec2 pixel = seen.pixel + (side == 0 ? 1.0 : -1.0) * *distance[side] * across;
      const Vec3 ray = RayThrough(view, seen, pixel);
      if (ray.cross(t).norm() < kMinSine) continue;
      const std::optional<EdgeConstraint> edge =
          ClosestApproach(axis, u, begin, end, view.center, ray, radius);
      // An edge this far off belongs to something else: another part of the
      // tube beside this one, the lead-in, a shadow left in the mask.
      if (edge && std::abs(radius - edge->distance) <= max_offset) edges->push_back(*edge);
    }
  }
}

AxisPointFit SilhouetteRefiner::FitAxisPoint(const Vec3& p, const Vec3& t, double radius,
                                             bool estimate_radius,
                                             const std::vector<EdgeConstraint>& edges) const {
  Vec3 b1;
  Vec3 b2;
  NormalBasis(t, &b1, &b2);
  EdgeSystem system(edges, b1, b2, radius, estimate_radius);
  // Enough edges to solve, and with the radius unknown, enough to check it.
  const int min_edges = estimate_radius ? 5 : 2;
  AxisPointFit fit;
  EdgeSystem::Solution solution = system.Solve();
  // While some edge disagrees, drop the one whose absence the others
  // explain best, if it stands out from them.
  while (solution.ok && solution.worst > kOutlierMm && system.active_count() > min_edges) {
    const EdgeSystem::Suspect suspect = system.MostInconsistent();
    const int others = system.active_count() - 1;
    const double others_rms = std::sqrt(suspect.others.sum_sq / std::max(1, others));
    if (!suspect.others.ok ||
        suspect.residual <= std::max(kOutlierMm, kOutlierFactor * others_rms)) {
      break;
    }
    system.Drop(suspect.index);
    solution = suspect.others;
  }
  if (!solution.ok || system.active_count() < min_edges) return fit;
  fit.ok = true;
  fit.point = p + solution.x[0] * b1 + solution.x[1] * b2;
  fit.radius = estimate_radius ? solution.x[2] : radius;
  fit.edges_used = system.active_count();
  fit.sum_sq_residual = solution.sum_sq;
  return fit;
}

bool SilhouetteRefiner::OutlineIsOwn(const View& view, const Vec3& p, const Vec3& t,
                                     double radius) const {
  AxisView seen;
  if (!ViewAxis(view, p, t, &seen)) return false;
  const Vec2 across(-seen.along.y(), seen.along.x());
  const double radius_px = RadiusPx(view, p, radius);
  const int max_steps = MaxSteps(radius_px, 4.0);
  const std::optional<double> a = FindEdgeAlong(*view.silhouette, seen.pixel, across, max_steps);
  const std::optional<double> b = FindEdgeAlong(*view.silhouette, seen.pixel, -across, max_steps);
  return a && b && std::abs(0.5 * (*a + *b) - radius_px) <= kWidthTolerance * radius_px + 1.0;
}

std::optional<double> SilhouetteRefiner::TipOffsetInView(const View& view, const Vec3& end,
                                                         const Vec3& t, double radius,
                                                         double* weight) const {
  AxisView axis;
  if (!ViewAxis(view, end, t, &axis)) return std::nullopt;
  // A camera that sees another part of the tube over the end would walk on
  // into it: the outline just behind the cap must be the tube's own.
  if (!OutlineIsOwn(view, end - (radius + 1.0) * t, t, radius)) return std::nullopt;
  // Room for the cap (one radius) and the largest move of the end.
  const double px_per_mm = RadiusPx(view, end, 1.0);
  const int max_steps = std::clamp(
      static_cast<int>(std::ceil(px_per_mm * (radius + kMaxTipShiftMm) + 2.0)), 4, kMaxWalk);
  const std::optional<double> distance =
      FindEdgeAlong(*view.silhouette, axis.pixel, axis.along, max_steps);
  if (!distance) return std::nullopt;
  const Vec3 ray = RayThrough(view, axis, axis.pixel + *distance * axis.along);
  // Distance of end + λt from the ray: |w0 + λ w1| with w0, w1 below; the
  // ray crosses the axis line at λ*, and the sphere centre lies on the near
  // side of the crossing, radius / |w1| before it.
  const Vec3 w0 = (end - view.center).cross(ray);
  const Vec3 w1 = t.cross(ray);
  const double sine_sq = w1.squaredNorm();
  if (sine_sq < kMinSine * kMinSine) return std::nullopt;
  const double offset = -w0.dot(w1) / sine_sq - radius / std::sqrt(sine_sq);
  if (std::abs(offset) > kMaxTipShiftMm) return std::nullopt;
  // Seen obliquely, a pixel spans more of the axis.
  *weight = sine_sq;
  return offset;
}

std::optional<double> SilhouetteRefiner::FitTipOffset(const Vec3& end, const Vec3& t,
                                                      double radius) const {
  std::vector<std::pair<double, double>> offsets;  // (λ, weight) per camera
  for (const View& view : views_) {
    double weight = 0.0;
    if (const std::optional<double> offset = TipOffsetInView(view, end, t, radius, &weight)) {
      offsets.emplace_back(*offset, weight);
    }
  }
  if (offsets.empty()) return std::nullopt;
  // The cameras that agree with the median (of two that disagree, the
  // smaller move) are averaged.
  std::sort(offsets.begin(), offsets.end());
  double reference = offsets[offsets.size() / 2].first;
  if (offsets.size() == 2 && offsets[1].first - offsets[0].first > kTipAgreementMm) {
    reference = std::abs(offsets[0].first) < std::abs(offsets[1].first) ? offsets[0].first
                                                                        : offsets[1].first;
  }
  double weighted_sum = 0.0;
  double weight_sum = 0.0;
  for (const auto& [offset, weight] : offsets) {
    if (std::abs(offset - reference) > kTipAgreementMm) continue;
    weighted_sum += weight * offset;
    weight_sum += weight;
  }
  return weighted_sum / weight_sum;
}

}  // namespace shapesense
