#include "libs/camera/rig_yaml.h"

#include <gtest/gtest.h>

#include <numbers>

#include "libs/core/error.h"
#include "tests/libs/camera/test_rig.h"

namespace shapesense {
namespace {

Rig ThreeCameraRig() {
  Rig rig;
  for (int i = 0; i < 3; ++i) {
    rig.cameras.push_back(
        testing::DistortedCamera("cam" + std::to_string(i), 2.0 * std::numbers::pi * i / 3.0));
  }
  rig.workspace_min = Vec3(-128, -128, -128);
  rig.workspace_max = Vec3(128, 128, 128);
  rig.base_point = Vec3(0, 0, -128);
  return rig;
}

TEST(RigYamlTest, RigRoundTripsThroughYaml) {
  const Rig rig = ThreeCameraRig();
  const Rig parsed = ParseRigYaml(FormatRigYaml(rig), "rig.yaml");
  ASSERT_EQ(parsed.cameras.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const Camera& a = rig.cameras[i];
    const Camera& b = parsed.cameras[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.width, b.width);
    EXPECT_TRUE(a.camera_matrix.isApprox(b.camera_matrix, 1e-15));
    EXPECT_TRUE(a.cam_from_world.matrix().isApprox(b.cam_from_world.matrix(), 1e-15));
    EXPECT_EQ(a.distortion, b.distortion);
  }
  EXPECT_EQ(parsed.base_point, rig.base_point);
  EXPECT_EQ(parsed.workspace_max, rig.workspace_max);
}

TEST(RigYamlTest, CameraRoundTripsThroughYaml) {
  const Camera camera = testing::DistortedCamera("left", 0.2);
  const Camera parsed = ParseCameraYaml(FormatCameraYaml(camera), "cam.yaml");
  EXPECT_EQ(parsed.name, "left");
  EXPECT_TRUE(parsed.camera_matrix.isApprox(camera.camera_matrix));
  EXPECT_EQ(parsed.distortion, camera.distortion);
}

void ExpectRejected(const std::string& text, const std::string& expected_fragment) {
  try {
    ParseRigYaml(text, "bad/rig.yaml");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("bad/rig.yaml"), std::string::npos) << message;
    EXPECT_NE(message.find(expected_fragment), std::string::npos) << message;
  }
}

TEST(RigYamlTest, MalformedRigsNameTheFileAndKey) {
  std::string good = FormatRigYaml(ThreeCameraRig());
  ExpectRejected("%YAML:1.0\n---\nfoo: 1\n", "cameras: missing");
  ExpectRejected("not: [valid", "not valid");
  std::string no_base = good.substr(0, good.find("base_point"));
  ExpectRejected(no_base, "base_point: missing");
  std::string bad_size = good;
  bad_size.replace(bad_size.find("image_width: 640"), 16, "image_width: -3");
  ExpectRejected(bad_size, "cameras[0].image_width: expected a positive integer");
  std::string small_matrix = good;
  const size_t at = small_matrix.find("rows: 3", small_matrix.find("rotation"));
  small_matrix.replace(at, 7, "rows: 1");
  ExpectRejected(small_matrix, "cameras[0].rotation");
}

TEST(RigYamlTest, DuplicateCameraNamesAreRejected) {
  Rig rig = ThreeCameraRig();
  rig.cameras[2].name = "cam0";
  ExpectRejected(FormatRigYaml(rig), "repeats");
}

}  // namespace
}  // namespace shapesense
