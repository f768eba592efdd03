#pragma once

// The simulated actuators' motion: an axis moves toward its target at up to
// a maximum speed and stops on it (no acceleration phase; enough for a plant
// whose own dynamics are slower).

#include <algorithm>
#include <cmath>

namespace shapesense {

struct AxisMotion {
  double position = 0.0;
  double target = 0.0;

  void Advance(double dt_s, double max_speed) {
    const double step = std::max(0.0, dt_s) * max_speed;
    const double gap = target - position;
    position = std::abs(gap) <= step ? target : position + std::copysign(step, gap);
  }
  // Hold where it is.
  void Hold() { target = position; }
  bool AtTarget() const { return position == target; }
};

}  // namespace shapesense
