// What the monitor makes of the rig's messages: pictures joined to their own
// frame-set's shape and silhouettes whatever the arrival order, the shape
// projected through the calibration, lost frame-sets counted from the
// triggers, programs missing once silent, the gate in one word.
#include "services/monitor/monitor_model.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "libs/control/safety_gate.h"
#include "libs/sim/scene_generators.h"

namespace shapesense {
namespace {

using nlohmann::json;

constexpr int64_t kStart = 1'700'000'000'000'000;
constexpr int64_t kPeriodUs = 33'333;

shape_t Shape(int64_t seq) {
  shape_t shape{};
  shape.trigger_seq = seq;
  shape.trigger_utime = kStart + seq * kPeriodUs;
  shape.valid = true;
  for (int i = 0; i <= 10; ++i) shape.centerline.push_back({0.0, 0.0, 10.0 * i});
  shape.num_points = static_cast<int32_t>(shape.centerline.size());
  shape.arc_length.assign(shape.centerline.size(), 0.0);
  shape.curvature.assign(shape.centerline.size(), 0.0);
  shape.markers = {{0.0, 0.0, 50.0}};
  shape.marker_arc_length = {50.0};
  shape.marker_std_mm = {0.05};
  shape.num_markers = 1;
  shape.tip[2] = 100.0;
  shape.stage_times.push_back({"carving", 3000, 0});
  shape.num_stage_times = 1;
  return shape;
}

image_t Preview(const std::string& camera, int64_t seq) {
  image_t preview{};
  preview.camera = camera;
  preview.width = 320;
  preview.height = 240;
  preview.compression = image_t::COMPRESSION_JPEG;
  preview.trigger_seq = seq;
  preview.trigger_utime = kStart + seq * kPeriodUs;
  preview.data = {0xff, 0xd8, 0xff, 0xd9};
  preview.size = 4;
  return preview;
}

silhouettes_t Silhouettes(int64_t seq, const std::string& camera) {
  silhouettes_t set{};
  set.trigger_seq = seq;
  set.trigger_utime = kStart + seq * kPeriodUs;
  silhouette_view_t view{};
  view.camera = camera;
  view.width = 640;
  view.height = 480;
  view.mask_row = {100, 101};
  view.mask_begin = {10, 11};
  view.mask_end = {20, 21};
  view.num_mask_runs = 2;
  set.views.push_back(view);
  set.num_views = 1;
  return set;
}

// A camera update's JSON header and its JPEG.
std::pair<json, std::string> Picture(const WebUpdate& update) {
  EXPECT_TRUE(update.binary);
  uint32_t length = 0;
  for (int i = 0; i < 4; ++i) {
    length |= static_cast<uint32_t>(static_cast<uint8_t>(update.payload[i])) << (8 * i);
  }
  return {json::parse(update.payload.substr(4, length)), update.payload.substr(4 + length)};
}

std::vector<WebUpdate> Pictures(const std::vector<WebUpdate>& updates) {
  std::vector<WebUpdate> pictures;
  for (const WebUpdate& update : updates) {
    if (update.channel.starts_with("camera/")) pictures.push_back(update);
  }
  return pictures;
}

json Find(const std::vector<WebUpdate>& updates, const std::string& channel) {
  for (const WebUpdate& update : updates) {
    if (update.channel == channel) return json::parse(update.payload);
  }
  ADD_FAILURE() << "no update on " << channel;
  return {};
}

class MonitorModelTest : public ::testing::Test {
 protected:
  MonitorModelTest() : rig_(MakeSyntheticRig({})), model_({}, rig_.cameras, std::nullopt, {}) {}
  const Camera& cam0() const { return rig_.cameras[0]; }

  Rig rig_;
  MonitorModel model_;
};

TEST_F(MonitorModelTest, APictureWaitsForItsOwnShapeAndCarriesItProjected) {
  EXPECT_TRUE(model_.OnPreview(Preview(cam0().name, 3)).empty());
  EXPECT_TRUE(model_.OnSilhouettes(Silhouettes(3, cam0().name), kStart).empty());
  const std::vector<WebUpdate> pictures =
      Pictures(model_.OnShape(Shape(3), kStart + 3 * kPeriodUs));
  ASSERT_EQ(pictures.size(), 1u);
  const auto [header, jpeg] = Picture(pictures[0]);
  EXPECT_EQ(header["trigger_seq"], 3);
  EXPECT_TRUE(Find(model_.OnTruth(Shape(3)), "truth")["valid"].is_boolean());
  EXPECT_EQ(header["width"], cam0().width);  // the overlays are in the camera's pixels
  EXPECT_EQ(jpeg, std::string("\xff\xd8\xff\xd9", 4));
  const Vec2 tip = *cam0().Project(Vec3(0, 0, 100));
  EXPECT_NEAR(header["tip"][0].get<double>(), tip.x(), 0.01);
  EXPECT_NEAR(header["tip"][1].get<double>(), tip.y(), 0.01);
  EXPECT_EQ(header["centerline"].size(), 11u);
  EXPECT_EQ(header["markers"].size(), 1u);
  EXPECT_EQ(header["silhouette"]["mask"], json::parse("[[100,10,20],[101,11,21]]"));
}

TEST_F(MonitorModelTest, AShapeBeforeItsPictureIsFoundWhenThePictureComes) {
  model_.OnShape(Shape(6), kStart);
  const std::vector<WebUpdate> pictures = Pictures(model_.OnPreview(Preview(cam0().name, 6)));
  ASSERT_EQ(pictures.size(), 1u);
  EXPECT_EQ(Picture(pictures[0]).first["centerline"].size(), 11u);
}

TEST_F(MonitorModelTest, APictureWhoseShapeWillNotComeGoesOutBare) {
  model_.OnPreview(Preview(cam0().name, 9));
  // Shapes come in trigger order: the shape of 10 says 9's is lost.
  const std::vector<WebUpdate> pictures = Pictures(model_.OnShape(Shape(10), kStart));
  ASSERT_EQ(pictures.size(), 1u);
  const json header = Picture(pictures[0]).first;
  EXPECT_EQ(header["trigger_seq"], 9);
  EXPECT_TRUE(header["centerline"].is_null());
  // With no shape service at all, a much younger picture releases it.
  model_.OnPreview(Preview(cam0().name, 100));
  EXPECT_EQ(Pictures(model_.OnPreview(Preview(cam0().name, 130))).size(), 1u);
}

TEST_F(MonitorModelTest, AnOverlayNeverComesFromAnotherFrameSet) {
  model_.OnSilhouettes(Silhouettes(20, cam0().name), kStart);
  model_.OnPreview(Preview(cam0().name, 21));
  const std::vector<WebUpdate> pictures = Pictures(model_.OnShape(Shape(21), kStart));
  ASSERT_EQ(pictures.size(), 1u);
  EXPECT_TRUE(Picture(pictures[0]).first["silhouette"].is_null());
}

TEST_F(MonitorModelTest, LostFrameSetsAreCountedFromTheTriggers) {
  for (const int64_t seq : {1, 2, 5, 6, 10}) model_.OnShape(Shape(seq), kStart + seq * kPeriodUs);
  const json stats = Find(model_.Tick(kStart + 10 * kPeriodUs), "stats");
  EXPECT_EQ(stats["lost_sets"], 2 + 3);
  EXPECT_EQ(stats["invalid_shapes"], 0);
  EXPECT_NEAR(stats["latency_ms"]["carving"].get<double>(), 3.0, 1e-9);
}

TEST_F(MonitorModelTest, AProgramFallenSilentIsMissing) {
  service_status_t status{};
  status.service = "shape";
  status.host = "camera";
  model_.OnStatus(status, kStart);
  const auto state = [&](int64_t now) {
    return Find(model_.Tick(now), "health")["rows"][0]["state"].get<std::string>();
  };
  EXPECT_EQ(state(kStart + 1'000'000), "up");
  EXPECT_EQ(state(kStart + 2'000'000), "stale");
  EXPECT_EQ(state(kStart + 2'600'000), "missing");
}

TEST_F(MonitorModelTest, TheGateIsSaidInOneWord) {
  tendon_command_t command{};
  command.mode = tendon_command_t::MODE_CLOSED_LOOP;
  command.displacement_mm = {1.0, 2.0, 3.0};
  command.num_tendons = 3;
  for (const auto& [reasons, word] : std::vector<std::pair<uint32_t, std::string>>{
           {0, "ok"},
           {kGateRateLimited, "ok"},
           {kGateSensingStale, "stale"},
           {kGateAwaitingSensing, "held"},
           {kGateSensingLost, "stopped"},
           {kGateEmergencyStop | kGateSensingLost, "estop"}}) {
    command.gate_reasons = static_cast<int32_t>(reasons);
    const json controller = Find(model_.OnTendonCommand(command), "controller");
    EXPECT_EQ(controller["gate"], word) << reasons;
    EXPECT_EQ(controller["mode"], "closed_loop");
  }
}

TEST_F(MonitorModelTest, TheControllersLoopRateIsThinnedButAChangeGoesOutAtOnce) {
  tendon_command_t command{};
  command.mode = tendon_command_t::MODE_CLOSED_LOOP;
  int sent = 0;
  for (int64_t step = 0; step < 100; ++step) {  // 1 s at 100 Hz
    command.header.utime = kStart + step * 10'000;
    sent += static_cast<int>(model_.OnTendonCommand(command).size());
  }
  EXPECT_EQ(sent, 20);
  command.header.utime += 1'000;
  command.gate_reasons = static_cast<int32_t>(kGateEmergencyStop);
  const std::vector<WebUpdate> updates = model_.OnTendonCommand(command);
  ASSERT_EQ(updates.size(), 1u);
  EXPECT_EQ(json::parse(updates[0].payload)["gate"], "estop");
  EXPECT_EQ(Find(model_.Tick(command.header.utime + 1'000), "controller")["gate"], "estop");
}

TEST_F(MonitorModelTest, TheHullGoesOutAFewTimesASecondAsVoxelCentres) {
  voxel_cloud_t cloud{};
  cloud.grid_origin[0] = -10.0;
  cloud.grid_origin[1] = 20.0;
  cloud.grid_origin[2] = 5.0;
  cloud.voxel_size = 0.5;
  cloud.dims[0] = 4;
  cloud.dims[1] = 3;
  cloud.dims[2] = 2;
  cloud.voxels = {0, 1 + 4 * (2 + 3 * 1)};  // (0, 0, 0) and (1, 2, 1)
  cloud.labels = {0, 0};
  cloud.num_voxels = 2;
  int sent = 0;
  for (int64_t seq = 0; seq < 30; ++seq) {  // 1 s at 30 Hz
    cloud.trigger_seq = seq;
    cloud.trigger_utime = kStart + seq * kPeriodUs;
    const std::vector<WebUpdate> updates = model_.OnVoxels(cloud);
    sent += static_cast<int>(updates.size());
    if (seq == 0) {
      ASSERT_EQ(updates.size(), 1u);
      EXPECT_TRUE(updates[0].foxglove_channel.empty());
      EXPECT_EQ(json::parse(updates[0].payload)["points"],
                json::parse("[-10.0, 20.0, 5.0, -9.5, 21.0, 5.5]"));
    }
  }
  EXPECT_EQ(sent, 4);
}

TEST(MonitorModelTargetTest, AConfigurationTargetIsDrawnFromTheModel) {
  TargetGeometry geometry;
  geometry.rest = {100.0, 60.0};
  geometry.world_from_base.translation() = Vec3(1, 2, 3);
  MonitorModel model({}, {}, std::nullopt, geometry);
  configuration_target_t target{};
  target.kind = configuration_target_t::KIND_CONFIGURATION;
  const std::vector<WebUpdate> updates = model.OnTarget(target);
  const json drawn = Find(updates, "target");
  ASSERT_TRUE(drawn["centerline"].is_array());
  // Straight (q = 0): the tip 160 mm along the base's y axis, from the base.
  EXPECT_NEAR(drawn["tip"][0].get<double>(), 1.0, 1e-6);
  EXPECT_NEAR(drawn["tip"][1].get<double>(), 2.0 + 160.0, 1e-6);
  EXPECT_NEAR(drawn["tip"][2].get<double>(), 3.0, 1e-6);
  model.OnShape(Shape(1), kStart);
  EXPECT_TRUE(Find(model.OnTendonCommand({}), "controller")["tip_error_mm"].is_number());
}

TEST(HelloJsonTest, NamesTheCamerasAndTheirFrusta) {
  const Rig rig = MakeSyntheticRig({});
  MonitorModelOptions options;
  options.estop_enabled = true;
  const json hello = json::parse(HelloJson(options, rig.cameras));
  EXPECT_EQ(hello["type"], "hello");
  EXPECT_TRUE(hello["estop_enabled"]);
  ASSERT_EQ(hello["cameras"].size(), rig.cameras.size());
  const json& frustum = hello["cameras"][0]["frustum"];
  ASSERT_EQ(frustum.size(), 5u);
  const Vec3 apex(frustum[0][0], frustum[0][1], frustum[0][2]);
  EXPECT_NEAR((apex - rig.cameras[0].Center()).norm(), 0.0, 0.01);
  // Each corner projects back onto its image corner.
  const Vec3 corner(frustum[3][0], frustum[3][1], frustum[3][2]);
  const Vec2 pixel = *rig.cameras[0].Project(corner);
  EXPECT_NEAR(pixel.x(), rig.cameras[0].width - 1.0, 0.05);
  EXPECT_NEAR(pixel.y(), rig.cameras[0].height - 1.0, 0.05);
}

}  // namespace
}  // namespace shapesense
