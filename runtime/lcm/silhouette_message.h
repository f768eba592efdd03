#pragma once

// silhouettes_t ⇄ compact silhouettes (libs/silhouette/compact_silhouette.h):
// what the carving service sends the shape service instead of the images.
#include <cstdint>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/silhouette/compact_silhouette.h"
#include "shapesense/silhouettes_t.hpp"

namespace shapesense {

// The compact silhouettes of one frame-set: what the shape stage refines against.
struct SilhouetteSet {
  int64_t trigger_seq = -1;
  int64_t trigger_utime = 0;
  std::vector<CompactSilhouette> views;  // one per camera, in the rig's order
};

// The set's trigger and one view per camera of `rig`; the header is the
// caller's. The runs' coordinates must fit in int16 (kMaxImageSide).
void SilhouettesToMessage(const Rig& rig, const SilhouetteSet& set, silhouettes_t* message);

// Checks that the message has one view per camera of `rig`, in its order and
// of its size, with consistent counts and well-formed runs
// (Validate(CompactSilhouette)), and fills `set`. "" or the reason, naming
// the camera.
std::string SilhouettesFromMessage(const silhouettes_t& message, const Rig& rig,
                                   SilhouetteSet* set);

}  // namespace shapesense
