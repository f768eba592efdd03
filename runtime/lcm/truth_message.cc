#include "runtime/lcm/truth_message.h"

#include <algorithm>
#include <cmath>

namespace shapesense {
namespace {

constexpr double kPointSpacing = 1.0;  // mm between published centreline points

std::vector<double> ArcLengths(const Polyline& points) {
  std::vector<double> arc(points.size(), 0.0);
  for (size_t i = 1; i < points.size(); ++i) {
    arc[i] = arc[i - 1] + (points[i] - points[i - 1]).norm();
  }
  return arc;
}

// Indices of the points kept: about kPointSpacing apart in arc length, both ends.
std::vector<size_t> Thinned(const std::vector<double>& arc) {
  std::vector<size_t> kept = {0};
  for (size_t i = 1; i + 1 < arc.size(); ++i) {
    if (arc[i] - arc[kept.back()] >= kPointSpacing - 1e-9) kept.push_back(i);
  }
  if (arc.size() > 1) kept.push_back(arc.size() - 1);
  return kept;
}

std::vector<double> Xyz(const Vec3& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

shape_t FrameSetTruth(const TubeScene& scene, const TrajectoryPose& pose, int64_t trigger_seq,
                      int64_t trigger_utime, int64_t header_seq, int64_t publish_utime) {
  const GroundTruth truth = TruthOf(scene);
  const std::vector<double> arc = ArcLengths(scene.centerline);
  shape_t shape{};
  shape.header.seq = header_seq;
  shape.header.utime = publish_utime;
  // Both times are the virtual rig's clock: what a receiver on another host
  // dates the truth by (header_t.data_age_us).
  shape.header.data_age_us = std::max<int64_t>(0, publish_utime - trigger_utime);
  shape.trigger_seq = trigger_seq;
  shape.trigger_utime = trigger_utime;
  shape.valid = true;
  for (const size_t i : Thinned(arc)) {
    shape.centerline.push_back(Xyz(scene.centerline[i]));
    shape.arc_length.push_back(arc[i]);
    shape.curvature.push_back(CurvatureAt(pose, arc[i]));
  }
  shape.num_points = static_cast<int32_t>(shape.centerline.size());
  for (const Vec3& marker : truth.markers) shape.markers.push_back(Xyz(marker));
  shape.marker_arc_length = truth.marker_arc_length;
  shape.marker_std_mm.assign(truth.markers.size(), 0.0);  // exact
  shape.num_markers = static_cast<int32_t>(shape.markers.size());
  std::copy_n(Xyz(truth.tip).begin(), 3, shape.tip);
  shape.length = truth.length;
  return shape;
}

}  // namespace shapesense
