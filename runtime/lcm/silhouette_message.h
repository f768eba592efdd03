#pragma once

// silhouettes_t ⇄ compact silhouettes (libs/silhouette/compact_silhouette.h):
// what the carving service sends the shape service instead of the images.
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/silhouette/compact_silhouette.h"
#include "shapesense/silhouettes_t.hpp"

namespace shapesense {

// One view per camera of `rig`, in its order; header and trigger are the
// caller's. The runs' coordinates must fit in int16 (kMaxImageSide).
void SilhouettesToMessage(const Rig& rig, const std::vector<CompactSilhouette>& compact,
                          silhouettes_t* message);

// Checks that the message has one view per camera of `rig`, in its order and
// of its size, with consistent counts and well-formed runs
// (Validate(CompactSilhouette)), and fills `compact` in the rig's order.
// "" or the reason, naming the camera.
std::string SilhouettesFromMessage(const silhouettes_t& message, const Rig& rig,
                                   std::vector<CompactSilhouette>* compact);

}  // namespace shapesense
