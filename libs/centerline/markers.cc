#include "libs/centerline/markers.h"

#include <algorithm>

#include "libs/centerline/curve_measures.h"
#include "libs/geometry/polyline.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {
namespace {

struct Cluster {
  Vec3 sum = Vec3::Zero();
  int count = 0;
};

MarkerOnCurve PlaceOnCurve(const Cluster& cluster, const Polyline& centerline,
                           const std::vector<double>& arc) {
  const ClosestPoint closest = ClosestPointOnPolyline(centerline, arc, cluster.sum / cluster.count);
  return {closest.arc_length, closest.point, cluster.count};
}

// Steps along the centreline when reading labels, mm.
constexpr double kLabelStep = 0.2;
// Read this far beyond the band's expected ends, mm: room for the voxels'
// error in its centre and the front-surface shift.
constexpr double kLabelMargin = 8.0;
// Half the widest band looked for, mm.
constexpr double kMaxHalfWidth = 8.0;

enum class Seen { kTape, kBody, kUnknown };

Seen LabelAt(const Camera& camera, const Silhouette& silhouette, const Vec2& pixel) {
  if (!camera.InImage(pixel)) return Seen::kUnknown;
  const int x = static_cast<int>(pixel.x() + 0.5);
  const int y = static_cast<int>(pixel.y() + 0.5);
  switch (silhouette.labels.at<uint8_t>(y, x)) {
    case kLabelMarker:
      return Seen::kTape;
    case kLabelBody:
      return Seen::kBody;
    default:
      return Seen::kUnknown;  // off the silhouette: the centreline is wrong here
  }
}

// The labels along the projected centreline from arc `first` to `last`, every
// kLabelStep. The centreline is projected every kProjectStep and the pixels
// interpolated between: the image of a curve is smooth on that scale.
void ReadLabels(const Camera& camera, const Silhouette& silhouette, const Polyline& centerline,
                const std::vector<double>& arc, double first, double last,
                std::vector<Seen>* seen) {
  constexpr int kSubsteps = 5;
  constexpr double kProjectStep = kLabelStep * kSubsteps;
  seen->clear();
  std::optional<Vec2> previous = camera.Project(PointAtArcLength(centerline, arc, first));
  for (double s = first; s + kProjectStep <= last + 1e-9; s += kProjectStep) {
    const std::optional<Vec2> next =
        camera.Project(PointAtArcLength(centerline, arc, s + kProjectStep));
    for (int k = 0; k < kSubsteps; ++k) {
      seen->push_back(previous && next ? LabelAt(camera, silhouette,
                                                 *previous + (*next - *previous) * k / kSubsteps)
                                       : Seen::kUnknown);
    }
    previous = next;
  }
}

// cot θ between the axis and the direction from p to the camera.
double FrontShiftPerRadius(const Camera& camera, const Vec3& p, const Vec3& tangent) {
  const Vec3 to_camera = (camera.Center() - p).normalized();
  const double sine = tangent.cross(to_camera).norm();
  return tangent.dot(to_camera) / std::max(sine, 1e-6);
}

// The band's centre as one camera sees it (shift not yet added back): the run
// of tape around `expected` with body on both sides; nullopt when the run
// reaches the window's end or meets an unknown label.
std::optional<double> RunCenter(const std::vector<Seen>& seen, double first, double expected) {
  const int n = static_cast<int>(seen.size());
  if (n < 3) return std::nullopt;
  const int guess =
      std::clamp(static_cast<int>(std::lround((expected - first) / kLabelStep)), 0, n - 1);
  // The tape sample nearest the guess.
  int start = -1;
  for (int d = 0; d < n && start < 0; ++d) {
    for (const int k : {guess - d, guess + d}) {
      if (k >= 0 && k < n && seen[static_cast<size_t>(k)] == Seen::kTape) {
        start = k;
        break;
      }
    }
  }
  if (start < 0) return std::nullopt;
  int low = start;
  int high = start;
  while (low > 0 && seen[static_cast<size_t>(low - 1)] == Seen::kTape) --low;
  while (high + 1 < n && seen[static_cast<size_t>(high + 1)] == Seen::kTape) ++high;
  if (low == 0 || high == n - 1) return std::nullopt;
  if (seen[static_cast<size_t>(low - 1)] != Seen::kBody ||
      seen[static_cast<size_t>(high + 1)] != Seen::kBody) {
    return std::nullopt;
  }
  // The ends lie halfway between the last body and the first tape samples.
  return first + kLabelStep * 0.5 * (low + high);
}

std::optional<double> RefineOneMarker(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                                      const Polyline& centerline, const std::vector<double>& arc,
                                      double radius, double center) {
  const double first = std::max(0.0, center - kMaxHalfWidth - kLabelMargin);
  const double last = std::min(arc.back(), center + kMaxHalfWidth + kLabelMargin);
  const Vec3 tangent = ChordTangent(centerline, arc, center, 2.0);
  std::vector<Seen> seen;
  double weighted = 0.0;
  double weights = 0.0;
  for (size_t k = 0; k < rig.cameras.size(); ++k) {
    const Camera& camera = rig.cameras[k];
    const cv::Mat& labels = silhouettes[k].labels;
    if (labels.type() != CV_8U || labels.cols != camera.width || labels.rows != camera.height) {
      continue;  // no labels (or not this camera's): no tape to read
    }
    const double shift =
        radius * FrontShiftPerRadius(camera, PointAtArcLength(centerline, arc, center), tangent);
    ReadLabels(camera, silhouettes[k], centerline, arc, first, last, &seen);
    const std::optional<double> run = RunCenter(seen, first, center - shift);
    if (!run || std::abs(*run + shift - center) > kLabelMargin) continue;
    // Seen obliquely, a pixel spans more of the axis: weight by sin² θ.
    const double sine_sq = 1.0 / (1.0 + (shift / radius) * (shift / radius));
    weighted += sine_sq * (*run + shift);
    weights += sine_sq;
  }
  if (weights <= 0.0) return std::nullopt;
  return weighted / weights;
}

}  // namespace

void RefineMarkersInImages(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                           const Polyline& centerline, const std::vector<double>& arc,
                           double radius, std::vector<MarkerOnCurve>* markers) {
  if (silhouettes.size() != rig.cameras.size() || centerline.size() < 2) return;
  for (MarkerOnCurve& marker : *markers) {
    const std::optional<double> center =
        RefineOneMarker(rig, silhouettes, centerline, arc, radius, marker.arc_length);
    if (!center) continue;
    marker.arc_length = std::clamp(*center, 0.0, arc.back());
    marker.point = PointAtArcLength(centerline, arc, marker.arc_length);
  }
  std::sort(markers->begin(), markers->end(), [](const MarkerOnCurve& a, const MarkerOnCurve& b) {
    return a.arc_length < b.arc_length;
  });
}

std::vector<MarkerOnCurve> FindMarkers(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, const Polyline& centerline,
                                       const std::vector<double>& arc, int min_voxels, double gap) {
  std::vector<MarkerOnCurve> markers;
  if (centerline.size() < 2 || cloud.labels.size() != cloud.voxels.size()) return markers;
  Cluster cluster;
  double last_distance = 0.0;
  const auto close_cluster = [&] {
    if (cluster.count >= min_voxels) markers.push_back(PlaceOnCurve(cluster, centerline, arc));
    cluster = Cluster();
  };
  for (const int32_t i : body.members) {
    if (cloud.labels[static_cast<size_t>(i)] != kLabelMarker) continue;
    const double distance = body.distance[static_cast<size_t>(i)];
    if (cluster.count > 0 && distance - last_distance > gap) close_cluster();
    cluster.sum += VoxelCenter(cloud.grid, graph.coordinates(i));
    ++cluster.count;
    last_distance = distance;
  }
  close_cluster();
  std::sort(markers.begin(), markers.end(), [](const MarkerOnCurve& a, const MarkerOnCurve& b) {
    return a.arc_length < b.arc_length;
  });
  return markers;
}

}  // namespace shapesense
