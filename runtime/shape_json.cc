#include "runtime/shape_json.h"

#include <cmath>

namespace shapesense {
namespace {

double Round(double value, double step) { return std::round(value / step) * step; }

nlohmann::json PointToJson(const Vec3& p) {
  return {Round(p.x(), 1e-4), Round(p.y(), 1e-4), Round(p.z(), 1e-4)};
}

template <class Points>
nlohmann::json PointsToJson(const Points& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const Vec3& p : points) out.push_back(PointToJson(p));
  return out;
}

nlohmann::json TimesToJson(const StageTimes& times, double load_ms) {
  return {{"load", Round(load_ms, 1e-3)},
          {"silhouette", Round(times.silhouette_ms, 1e-3)},
          {"carving", Round(times.carving_ms, 1e-3)},
          {"shape", Round(times.shape_ms, 1e-3)},
          {"total", Round(load_ms + times.Total(), 1e-3)}};
}

}  // namespace

nlohmann::json ShapeToJson(const std::string& frame, const ShapeEstimate& shape,
                           const StageTimes& times, double load_ms) {
  nlohmann::json line = {{"frame", frame}, {"valid", shape.valid}};
  if (!shape.valid) {
    line["error"] = shape.error;
  } else {
    nlohmann::json curvature = nlohmann::json::array();
    for (const double k : shape.curvature) curvature.push_back(Round(k, 1e-7));
    nlohmann::json point_arc = nlohmann::json::array();
    for (const double s : shape.arc_length) point_arc.push_back(Round(s, 1e-4));
    nlohmann::json marker_arc = nlohmann::json::array();
    for (const double s : shape.marker_arc_length) marker_arc.push_back(Round(s, 1e-4));
    line["centerline"] = PointsToJson(shape.centerline);
    line["markers"] = PointsToJson(shape.markers);
    line["tip"] = PointToJson(shape.tip);
    line["arc_length"] = Round(shape.length, 1e-4);
    line["curvature"] = std::move(curvature);
    line["point_arc_length"] = std::move(point_arc);
    line["marker_arc_length"] = std::move(marker_arc);
    nlohmann::json marker_std = nlohmann::json::array();
    for (const double s : shape.marker_std) marker_std.push_back(Round(s, 1e-4));
    line["marker_std_mm"] = std::move(marker_std);
    line["tube_radius"] = Round(shape.tube_radius, 1e-4);
    line["silhouette_residual_mm"] = Round(shape.silhouette_residual_mm, 1e-5);
  }
  line["stage_ms"] = TimesToJson(times, load_ms);
  return line;
}

nlohmann::json FrameErrorToJson(const std::string& frame, const std::string& error) {
  return {{"frame", frame}, {"valid", false}, {"error", error}};
}

}  // namespace shapesense
