#include "clients/tools/demo/demo_scorer.h"

#include <cstdlib>

#include "runtime/lcm/shape_message.h"

namespace shapesense {
namespace {

Vec3 ToVec3(const double (&p)[3]) { return Vec3(p[0], p[1], p[2]); }

template <class Points>
Points ToPoints(const std::vector<std::vector<double>>& points) {
  Points out;
  out.reserve(points.size());
  for (const std::vector<double>& p : points) {
    if (p.size() == 3) out.emplace_back(p[0], p[1], p[2]);
  }
  return out;
}

}  // namespace

GroundTruth GroundTruthFromMessage(const shape_t& truth) {
  GroundTruth out;
  out.centerline = ToPoints<Polyline>(truth.centerline);
  out.tip = ToVec3(truth.tip);
  out.length = truth.length;
  out.markers = ToPoints<std::vector<Vec3>>(truth.markers);
  out.marker_arc_length = truth.marker_arc_length;
  return out;
}

DemoScorer::DemoScorer(int64_t match_tolerance_us) : live_(match_tolerance_us) {}

void DemoScorer::AddTruth(const shape_t& truth) { live_.AddTruth(truth); }

void DemoScorer::AddStatus(const service_status_t& status) {
  live_.AddStatus(status);
  services_.insert(status.service);
}

void DemoScorer::AddShape(const shape_t& shape, int64_t receive_utime) {
  live_.AddShape(shape, receive_utime);
  shapes_[shape.trigger_seq] = shape;
  ShapeEstimate estimate;
  if (!shape.valid || !ShapeFromMessage(shape, &estimate).empty() || !estimate.valid) {
    ++invalid_;
    return;
  }
  const shape_t* truth = live_.FindTruth(shape.trigger_utime);
  if (truth == nullptr || truth->centerline.size() < 2) return;
  errors_.push_back(CompareShape(estimate, GroundTruthFromMessage(*truth)));
}

DemoScore DemoScorer::Finish(int64_t end_utime) const {
  return {live_.Finish(end_utime), Summarize(errors_, invalid_)};
}

}  // namespace shapesense
