#include "libs/sim/ray_table.h"

#include <gtest/gtest.h>

#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

TEST(RayTableTest, AgreesWithTheCameraInverseModelAtEveryPixel) {
  for (uint32_t seed = 0; seed < 3; ++seed) {
    SyntheticRigOptions options;
    options.seed = seed;
    options.image_width = 333;  // not a multiple of the table's grid
    options.image_height = 251;
    const Rig rig = MakeSyntheticRig(options);
    for (const Camera& camera : rig.cameras) {
      const RayTable table = BuildRayTable(camera);
      ASSERT_EQ(table.rays.size(), static_cast<size_t>(camera.width * camera.height));
      const Mat3 cam_from_world = camera.cam_from_world.linear();
      double worst = 0.0;
      for (int v = 0; v < camera.height; ++v) {
        for (int u = 0; u < camera.width; ++u) {
          const Vec3 expected = cam_from_world * camera.RayDirectionWorld(Vec2(u, v));
          const RayTable::Ray& ray = table.at(u, v);
          worst = std::max(worst, (Vec3(ray.x, ray.y, ray.z) - expected).norm());
        }
      }
      EXPECT_LT(worst, 5e-7) << camera.name << " seed " << seed;  // float precision
    }
  }
}

TEST(RayTableTest, PixelSizeIsTheAngleBetweenNeighbouringRays) {
  const Rig rig = MakeSyntheticRig({});
  const Camera& camera = rig.cameras[1];
  const RayTable table = BuildRayTable(camera);
  for (int v = 1; v < camera.height - 1; v += 17) {
    for (int u = 1; u < camera.width - 1; u += 23) {
      const auto direction = [&](int x, int y) {
        const RayTable::Ray& ray = table.at(x, y);
        return Vec3(ray.x, ray.y, ray.z);
      };
      const Vec3 du = 0.5 * (direction(u + 1, v) - direction(u - 1, v));
      const Vec3 dv = 0.5 * (direction(u, v + 1) - direction(u, v - 1));
      const double expected = std::sqrt(du.cross(dv).norm());
      EXPECT_NEAR(table.at(u, v).pixel_size, expected, 0.002 * expected) << u << " " << v;
    }
  }
}

}  // namespace
}  // namespace shapesense
