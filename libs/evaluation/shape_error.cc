#include "libs/evaluation/shape_error.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

double MaxDistanceToPolyline(const Polyline& points, const Polyline& line) {
  const std::vector<double> arc = CumulativeArcLength(line);
  double worst = 0.0;
  for (const Vec3& p : points)
    worst = std::max(worst, ClosestPointOnPolyline(line, arc, p).distance);
  return worst;
}

void CompareMarkers(const ShapeEstimate& estimate, const GroundTruth& truth, ShapeError* error) {
  error->markers_expected = static_cast<int>(truth.markers.size());
  error->markers_found = static_cast<int>(estimate.markers.size());
  if (truth.markers.empty()) return;
  double sum_sq = 0.0;
  for (const Vec3& expected : truth.markers) {
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3& found : estimate.markers)
      nearest = std::min(nearest, (found - expected).norm());
    sum_sq += nearest * nearest;
    error->marker_max = std::max(error->marker_max, nearest);
  }
  error->marker_rms = std::sqrt(sum_sq / static_cast<double>(truth.markers.size()));
}

// Applies `combine` to every figure of `into` and `from`.
template <class Combine>
void ForEachFigure(ShapeError& into, const ShapeError& from, Combine combine) {
  combine(into.centerline_rms, from.centerline_rms);
  combine(into.centerline_max, from.centerline_max);
  combine(into.coverage_rms, from.coverage_rms);
  combine(into.tip, from.tip);
  combine(into.length, from.length);
  combine(into.marker_rms, from.marker_rms);
  combine(into.marker_max, from.marker_max);
}

}  // namespace

ShapeError CompareShape(const ShapeEstimate& estimate, const GroundTruth& truth) {
  ShapeError error;
  error.centerline_rms = RmsDistanceToPolyline(estimate.centerline, truth.centerline);
  error.centerline_max = MaxDistanceToPolyline(estimate.centerline, truth.centerline);
  error.coverage_rms = RmsDistanceToPolyline(truth.centerline, estimate.centerline);
  error.tip = (estimate.tip - truth.tip).norm();
  error.length = std::abs(estimate.length - truth.length);
  CompareMarkers(estimate, truth, &error);
  return error;
}

ShapeErrorSummary Summarize(const std::vector<ShapeError>& errors, int failed) {
  ShapeErrorSummary summary;
  summary.frames = static_cast<int>(errors.size()) + failed;
  summary.failed = failed;
  for (const ShapeError& e : errors) {
    ForEachFigure(summary.mean, e, [](double& a, double b) { a += b; });
    ForEachFigure(summary.max, e, [](double& a, double b) { a = std::max(a, b); });
    summary.mean.markers_expected += e.markers_expected;
    summary.mean.markers_found += std::min(e.markers_found, e.markers_expected);
  }
  if (!errors.empty()) {
    const double n = static_cast<double>(errors.size());
    ForEachFigure(summary.mean, summary.mean, [n](double& a, double) { a /= n; });
  }
  return summary;
}

}  // namespace shapesense
