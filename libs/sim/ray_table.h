#pragma once

#include <vector>

#include "libs/camera/camera.h"

// Internal to the renderer (renderer.cc); declared here for its tests.

namespace shapesense {

// The viewing ray of every pixel centre of one camera, in the camera frame
// (the rays start at the origin), with lens distortion inverted. Row-major.
struct RayTable {
  struct Ray {
    float x, y, z;     // unit direction
    float pixel_size;  // angle one pixel subtends along the ray, rad
  };
  // A rectangle of undistorted normalised coordinates (x/z, y/z) holding the
  // image and a few pixels around it, where the lens model is invertible.
  struct Bounds {
    double x0, y0, x1, y1;
  };
  int width = 0;
  int height = 0;
  std::vector<Ray> rays;
  Bounds image_bounds{0.0, 0.0, 0.0, 0.0};

  const Ray& at(int u, int v) const { return rays[static_cast<size_t>(v) * width + u]; }
};

// Builds the table from the camera's inverse distortion, evaluated exactly on
// a coarse grid and carried to every pixel by interpolation plus one Newton
// step on the forward model (Camera::DistortAndScale); the directions agree
// with Camera::RayDirectionWorld to float precision (~1e-7 rad) at a fraction
// of the cost of solving every pixel.
RayTable BuildRayTable(const Camera& camera);

}  // namespace shapesense
