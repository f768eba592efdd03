#include "libs/mechanics/base_pose.h"

#include <cmath>

#include "libs/core/error.h"

namespace shapesense {
namespace {

std::string ExpectFinite(const char* key, const std::array<double, 3>& values) {
  for (const double value : values) {
    if (!std::isfinite(value))
      return std::string(key) + ": expected finite numbers, got " + Number(value);
  }
  return {};
}

}  // namespace

std::string BasePose::Validate() const {
  if (std::string error = ExpectFinite("base_position", base_position); !error.empty()) {
    return error;
  }
  return ExpectFinite("base_rotation", base_rotation);
}

Pose3 BasePose::WorldFromBase() const {
  return PoseFromRotationVector(Vec3(base_rotation.data()), Vec3(base_position.data()));
}

}  // namespace shapesense
