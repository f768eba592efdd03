#pragma once

// What comes in over LCM, checked before the controller uses it: sensed
// shapes (their configuration q and trigger time) and streamed targets.

#include <cstdint>
#include <string>

#include "libs/control/targets.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense {

enum class ShapeUse {
  kUsable,           // a configuration to close the loop on
  kNoConfiguration,  // measured without q (the shape service says why): not an error
  kMalformed,        // rejected and counted
};

// Whether `shape` carries a usable configuration; *why says why not.
// Malformed: q not finite, no trigger time, an age at publish that is
// negative or past an hour. (Its trigger time is the camera host's clock,
// so it is never compared with this one.)
ShapeUse CheckShape(const shape_t& shape, std::string* why);

// The shape to keep in the controller's LCM log: q, times and residuals,
// without the centreline and markers.
shape_t LoggedShape(const shape_t& shape);

// A streamed target as a Target (its time unused), or "" and *why: an
// unknown kind, a duration that is negative or not a number, a start time
// more than a minute from `now_utime`. Reachability is the resolver's.
bool TargetFromMessage(const configuration_target_t& message, int64_t now_utime, Target* target,
                       std::string* why);

// The target of a streamed move at time t: from `from` to `to` over
// [start, start + duration], linear in q.
struct TargetRamp {
  Configuration from = Configuration::Zero();
  Configuration to = Configuration::Zero();
  double start = 0.0;
  double duration = 0.0;

  Configuration At(double time) const;
};

}  // namespace shapesense
