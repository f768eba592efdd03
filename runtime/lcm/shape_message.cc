#include "runtime/lcm/shape_message.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "libs/core/error.h"
#include "runtime/lcm/stage_times.h"

namespace shapesense {
namespace {

bool AllFinite(const std::vector<double>& values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

bool AllFinitePoints(const std::vector<std::vector<double>>& points) {
  return std::all_of(points.begin(), points.end(),
                     [](const std::vector<double>& p) { return p.size() == 3 && AllFinite(p); });
}

std::vector<double> ToRow(const Vec3& p) { return {p.x(), p.y(), p.z()}; }
Vec3 FromRow(const std::vector<double>& row) { return Vec3(row[0], row[1], row[2]); }

}  // namespace

shape_t ShapeToMessage(const ShapeEstimate& shape) {
  shape_t message{};
  message.valid = shape.valid;
  message.error = shape.error;
  for (const Vec3& p : shape.centerline) message.centerline.push_back(ToRow(p));
  message.num_points = static_cast<int32_t>(message.centerline.size());
  message.arc_length = shape.arc_length;
  message.curvature = shape.curvature;
  message.arc_length.resize(message.centerline.size(), 0.0);
  message.curvature.resize(message.centerline.size(), 0.0);
  for (const Vec3& p : shape.markers) message.markers.push_back(ToRow(p));
  message.num_markers = static_cast<int32_t>(message.markers.size());
  message.marker_arc_length = shape.marker_arc_length;
  message.marker_arc_length.resize(message.markers.size(), 0.0);
  message.marker_std_mm = shape.marker_std;
  message.marker_std_mm.resize(message.markers.size(), 0.0);
  for (int axis = 0; axis < 3; ++axis) message.tip[axis] = shape.tip[axis];
  message.length = shape.length;
  message.centerline_residual_mm = shape.silhouette_residual_mm;
  return message;
}

std::string ValidateShapeMessage(const shape_t& message) {
  const size_t points = message.centerline.size();
  if (message.num_points < 0 || static_cast<size_t>(message.num_points) != points ||
      message.arc_length.size() != points || message.curvature.size() != points) {
    return Expected("num_points", "as many centreline points, arc lengths and curvatures",
                    std::to_string(message.num_points));
  }
  const size_t markers = message.markers.size();
  if (message.num_markers < 0 || static_cast<size_t>(message.num_markers) != markers ||
      message.marker_arc_length.size() != markers || message.marker_std_mm.size() != markers) {
    return Expected("num_markers", "as many markers, marker arc lengths and standard errors",
                    std::to_string(message.num_markers));
  }
  if (!AllFinitePoints(message.centerline) || !AllFinitePoints(message.markers) ||
      !AllFinite(message.arc_length) || !AllFinite(message.curvature) ||
      !AllFinite(message.marker_arc_length) || !AllFinite(message.marker_std_mm) ||
      !std::isfinite(message.length)) {
    return Expected("centerline, markers, arc lengths, curvature, length", "finite numbers",
                    "others");
  }
  if (message.valid && points < 2)
    return Expected("num_points", ">= 2 for a valid shape", std::to_string(points));
  if (message.has_configuration && (!std::all_of(std::begin(message.q), std::end(message.q),
                                                 [](double v) { return std::isfinite(v); }) ||
                                    !std::isfinite(message.configuration_residual_mm))) {
    return Expected("q, configuration_residual_mm", "finite numbers", "others");
  }
  return ValidateStageTimes(message.num_stage_times, message.stage_times);
}

std::string ShapeFromMessage(const shape_t& message, ShapeEstimate* shape) {
  if (std::string error = ValidateShapeMessage(message); !error.empty()) return error;
  *shape = ShapeEstimate{};
  shape->valid = message.valid;
  shape->error = message.error;
  for (const auto& row : message.centerline) shape->centerline.push_back(FromRow(row));
  shape->arc_length = message.arc_length;
  shape->curvature = message.curvature;
  for (const auto& row : message.markers) shape->markers.push_back(FromRow(row));
  shape->marker_arc_length = message.marker_arc_length;
  shape->marker_std = message.marker_std_mm;
  shape->tip = Vec3(message.tip[0], message.tip[1], message.tip[2]);
  shape->length = message.length;
  shape->silhouette_residual_mm = message.centerline_residual_mm;
  return {};
}

void SetMessageConfiguration(const Configuration& q, double residual_mm, shape_t* message) {
  message->has_configuration = true;
  for (int i = 0; i < 4; ++i) message->q[i] = q(i);
  message->configuration_residual_mm = residual_mm;
}

std::optional<Configuration> MessageConfiguration(const shape_t& message) {
  if (!message.has_configuration) return std::nullopt;
  return Configuration(message.q[0], message.q[1], message.q[2], message.q[3]);
}

}  // namespace shapesense
