#include "libs/camera/camera.h"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>

#include "tests/libs/camera/test_rig.h"

namespace shapesense {
namespace {

TEST(CameraTest, ProjectionAgreesWithOpenCv) {
  const Camera camera = testing::DistortedCamera("cam0", 0.3);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> coord(-80.0, 80.0);
  std::vector<cv::Point3d> points;
  for (int i = 0; i < 200; ++i) points.emplace_back(coord(rng), coord(rng), coord(rng));
  cv::Mat k, rvec, tvec, r;
  cv::eigen2cv(camera.camera_matrix, k);
  const Mat3 rotation = camera.cam_from_world.linear();
  const Vec3 translation = camera.cam_from_world.translation();
  cv::eigen2cv(rotation, r);
  cv::eigen2cv(translation, tvec);
  cv::Rodrigues(r, rvec);
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, rvec, tvec, k,
                    std::vector<double>(camera.distortion.begin(), camera.distortion.end()),
                    expected);
  for (size_t i = 0; i < points.size(); ++i) {
    const auto pixel = camera.Project(Vec3(points[i].x, points[i].y, points[i].z));
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR(pixel->x(), expected[i].x, 1e-9);
    EXPECT_NEAR(pixel->y(), expected[i].y, 1e-9);
  }
}

TEST(CameraTest, UndistortInvertsDistortAcrossTheImage) {
  const Camera camera = testing::DistortedCamera("cam0", 0.0);
  for (double u = 0; u < camera.width; u += 37) {
    for (double v = 0; v < camera.height; v += 29) {
      const Vec2 normalized = camera.UnscaleAndUndistort(Vec2(u, v));
      const Vec2 back = camera.DistortAndScale(normalized);
      EXPECT_NEAR(back.x(), u, 1e-8);
      EXPECT_NEAR(back.y(), v, 1e-8);
    }
  }
}

TEST(CameraTest, RayThroughAProjectionPassesThroughThePoint) {
  const Camera camera = testing::DistortedCamera("cam0", 1.1);
  const Vec3 point(12.0, -30.0, 25.0);
  const Vec3 ray = camera.RayDirectionWorld(*camera.Project(point));
  const Vec3 to_point = point - camera.Center();
  EXPECT_NEAR(ray.cross(to_point).norm() / to_point.norm(), 0.0, 1e-9);
  EXPECT_GT(ray.dot(to_point), 0.0);
}

TEST(CameraTest, PointBehindTheCameraHasNoProjection) {
  const Camera camera = testing::DistortedCamera("cam0", 0.0);
  EXPECT_FALSE(camera.Project(camera.Center() * 2.0).has_value());
}

TEST(CameraTest, ValidateNamesWhatIsWrong) {
  Camera camera = testing::DistortedCamera("cam0", 0.0);
  EXPECT_EQ(camera.Validate(), "");
  camera.camera_matrix(0, 0) = -1.0;
  EXPECT_NE(camera.Validate().find("focal"), std::string::npos);
  camera = testing::DistortedCamera("cam0", 0.0);
  camera.cam_from_world.linear() *= 2.0;
  EXPECT_NE(camera.Validate().find("rotation"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
