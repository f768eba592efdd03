#include "libs/mechanics/base_pose.h"

#include <cmath>

#include "libs/core/error.h"

namespace shapesense {
namespace {

std::string ExpectAllFinite(const char* key, const std::array<double, 3>& values) {
  for (const double value : values) {
    if (std::string error = ExpectFinite(key, value); !error.empty()) return error;
  }
  return {};
}

}  // namespace

std::string BasePose::Validate() const {
  if (std::string error = ExpectAllFinite("base_position", base_position); !error.empty()) {
    return error;
  }
  return ExpectAllFinite("base_rotation", base_rotation);
}

Pose3 BasePose::WorldFromBase() const {
  return PoseFromRotationVector(Vec3(base_rotation.data()), Vec3(base_position.data()));
}

}  // namespace shapesense
