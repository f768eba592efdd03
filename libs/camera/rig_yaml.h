#pragma once

#include <string>

#include "libs/camera/camera.h"

namespace shapesense {

// The rig file, OpenCV FileStorage YAML (see docs/dataset.md):
//   cameras: [{name, image_width, image_height, camera_matrix (3x3),
//              distortion_coefficients (1x5), rotation (3x3), translation (3x1, mm)}]
//   workspace_min, workspace_max, base_point: 1x3, mm.
// Parsing and formatting work on text; reading the file is the caller's job.
// Throws InputError naming `source`, the key and what was expected.
Rig ParseRigYaml(const std::string& text, const std::string& source);
std::string FormatRigYaml(const Rig& rig);

// A single camera in the same keys (the calibration tools' output).
Camera ParseCameraYaml(const std::string& text, const std::string& source);
std::string FormatCameraYaml(const Camera& camera);

}  // namespace shapesense
