#pragma once

// Where the manipulator's base stands in the cameras' world, as the configs
// give it: the shape service's `configuration:` section (to sense q) and
// the virtual rig's plant (to draw the shape of a q) read the same two keys,
// and must agree, or the sensed q is not the plant's.
#include <array>
#include <string>

#include "libs/geometry/types.h"

namespace shapesense {

// world_from_base: x_world = R x_base + base_position (mm), R the rotation
// by the rotation vector base_rotation (unit axis times angle, rad). The
// base frame's y axis runs along the manipulator: [1.5707963267948966, 0, 0]
// turns it onto world +z.
struct BasePose {
  std::array<double, 3> base_position = {0.0, 0.0, 0.0};
  std::array<double, 3> base_rotation = {0.0, 0.0, 0.0};

  // The two keys sit beside the owner's own (call from its VisitFields with
  // its visitor).
  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("base_position", base_position, "world_from_base: the base's origin in the world, mm");
    visit("base_rotation", base_rotation,
          "world_from_base: rotation vector (axis * angle, rad); [1.5707963267948966, 0, 0] "
          "turns the base's y axis (along the manipulator) onto world +z");
  }
  // "" or the key that is not finite.
  std::string Validate() const;
  Pose3 WorldFromBase() const;
};

}  // namespace shapesense
