#pragma once

// Camera frames as image_t messages (runtime/lcm/image_codec.h decodes them).

#include <cstdint>
#include <string>

#include "services/capture/camera_backend.h"
#include "shapesense/image_t.hpp"

namespace shapesense {

enum class ImageCompression { kNone, kPng };

// Parses "none" | "png"; std::invalid_argument otherwise.
ImageCompression ParseCompression(const std::string& name);

// The message of one frame of camera `camera`, `seq` on its channel, published
// at `publish_utime`: BGR8 or MONO8 rows (or their PNG), the trigger and
// device times, and stage "capture" = trigger to image received (for a
// free-running camera, from its exposure time when known). Throws
// std::invalid_argument for an image that is not 8-bit mono or BGR.
image_t ToImageMessage(const std::string& camera, const CameraFrame& frame, int64_t seq,
                       int64_t publish_utime, ImageCompression compression, int png_level = 1);

}  // namespace shapesense
