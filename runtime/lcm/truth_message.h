#pragma once

#include <cstdint>

#include "libs/sim/trajectory.h"
#include "libs/sim/tube_scene.h"
#include "shapesense/shape_t.hpp"

namespace shapesense {

// The ground truth of one frame-set as the shape message the pipeline would
// publish for it (channels::kTruth): the scene's centreline thinned to points
// about 1 mm apart (both ends kept) with their arc length and the pose's
// exact curvature, tape markers, tip, length; valid, no configuration.
// `trigger_seq` is the rig-sim's frame-set counter, `trigger_utime` when the
// set's first trigger reached the rig-sim; `header_seq` counts messages.
shape_t FrameSetTruth(const TubeScene& scene, const TrajectoryPose& pose, int64_t trigger_seq,
                      int64_t trigger_utime, int64_t header_seq, int64_t publish_utime);

}  // namespace shapesense
