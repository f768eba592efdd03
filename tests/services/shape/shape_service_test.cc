// The shape service in process over memq://, behind the carving service and
// on its own: shapes within 1 mm RMS of the truth with every stage time,
// pairing of voxel clouds with their silhouettes in either order, measuring
// unrefined after the pairing timeout or on silhouettes of another
// frame-set, malformed messages on every channel it listens to counted and
// survived, config checks.
#include "services/shape/shape_service.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "libs/core/error.h"
#include "libs/sim/tube_scene.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/stage_times.h"
#include "services/carving/carving_service.h"
#include "tests/support/service_test_options.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

using testing::Encode;
using testing::HandleUntil;
using testing::RawBytes;
using testing::TestRig;

const char* const kStages[] = {"capture", "transport", "silhouette", "carving", "shape"};

class ShapeServiceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new TestRig(4); }
  static void TearDownTestSuite() { delete rig_; }

  void Publish(const std::vector<image_t>& images) {
    for (const image_t& image : images) bus_.Publish(channels::Image(image.camera), image);
  }
  void SubscribeShapes() {
    bus_.Subscribe<shape_t>(channels::kShape, [this](const shape_t& s, const std::string&,
                                                     int64_t) { shapes_.push_back(s); });
  }
  bool HandleUntilShapes(size_t n, const std::function<void(int64_t)>& poll) {
    return HandleUntil(
        bus_, [&] { return shapes_.size() >= n; }, poll);
  }
  // What the carving stage makes of scene i: the voxel cloud and the compact silhouettes.
  CarvingOutput Carve(int scene, int64_t seq, int64_t trigger_utime) {
    const CarvingServiceOptions options = testing::TestCarvingOptions();
    const CarvingStage stage(rig_->rig(), rig_->backgrounds(), options.silhouette, options.carving);
    FrameSetAssembler assembler(CameraNames(rig_->rig()), options.assembly);
    CarvingOutput out;
    for (image_t& image : rig_->Messages(scene, seq, trigger_utime)) {
      AssemblyResult result = assembler.Add(std::move(image), NowUtime());
      if (result.completed) {
        EXPECT_EQ(stage.Process(*result.completed, &out), "");
      }
    }
    return out;
  }

  static TestRig* rig_;
  LcmBus bus_{"memq://"};
  std::vector<shape_t> shapes_;
};
TestRig* ShapeServiceTest::rig_ = nullptr;

TEST_F(ShapeServiceTest, BehindTheCarvingServiceEveryFrameSetIsMeasuredWithinAMillimetre) {
  CarvingService carving(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  ShapeService shape(testing::TestShapeOptions(), rig_->rig(), bus_);
  SubscribeShapes();
  constexpr int kSets = 4;
  std::map<std::string, double> stage_ms;
  for (int i = 0; i < kSets; ++i) {
    std::vector<image_t> images = rig_->Messages(i, 100 + i, 0);
    testing::Stamp(&images, NowUtime());
    Publish(images);
    // One set at a time, as a rig at a modest rate delivers them: the stage
    // times then tell each stage's own latency, not a queue's.
    ASSERT_TRUE(HandleUntilShapes(static_cast<size_t>(i + 1), [&](int64_t now) {
      carving.Poll(now);
      shape.Poll(now);
    }));
    const shape_t& measured = shapes_.back();
    EXPECT_EQ(measured.trigger_seq, 100 + i);
    ASSERT_TRUE(measured.valid) << measured.error;
    ShapeEstimate estimate;
    ASSERT_EQ(ShapeFromMessage(measured, &estimate), "");
    const double rms = testing::TwoWayRms(estimate.centerline, TruthOf(rig_->Scene(i)).centerline);
    EXPECT_LT(rms, 1.0);
    EXPECT_GT(measured.centerline_residual_mm, 0.0);  // refined against the silhouettes
    ASSERT_EQ(measured.num_stage_times, 5);
    for (const char* stage : kStages) {
      const stage_time_t* time = FindStageTime(measured.stage_times, stage);
      ASSERT_NE(time, nullptr) << stage;
      stage_ms[stage] += static_cast<double>(time->duration_us) * 1e-3 / kSets;
    }
    std::printf(
        "frame-set %d: centreline RMS %.3f mm, trigger to shape published %.2f ms\n", i, rms,
        static_cast<double>(measured.stage_times.back().end_utime - measured.trigger_utime) * 1e-3);
  }
  std::printf("mean stage times, ms (capture is the test's stand-in):");
  for (const char* stage : kStages) std::printf(" %s %.3f", stage, stage_ms[stage]);
  std::printf("\n");
  // The service counts a shape after publishing it.
  HandleUntil(bus_, [&] { return shape.Status(NowUtime()).published == kSets; });
  const service_status_t status = shape.Status(NowUtime());
  EXPECT_EQ(status.service, "shape");
  EXPECT_EQ(status.received, kSets);
  EXPECT_EQ(status.published, kSets);
  EXPECT_EQ(status.dropped + status.rejected + status.errors, 0) << status.last_error;
}

TEST_F(ShapeServiceTest, AVoxelCloudThatComesBeforeItsSilhouettesWaitsForThem) {
  ShapeService shape(testing::TestShapeOptions(), rig_->rig(), bus_);
  SubscribeShapes();
  const int64_t trigger = NowUtime();
  const CarvingOutput carved = Carve(0, 7, trigger);
  // Another frame-set's silhouettes first: they must not pair with this cloud.
  const CarvingOutput other = Carve(1, 6, trigger - 10'000);
  bus_.Publish(channels::kSilhouettes, other.silhouettes_message);
  bus_.Publish(channels::kVoxels, carved.message);
  ASSERT_TRUE(HandleUntil(bus_, [&] { return shape.Status(NowUtime()).received == 1; }));
  EXPECT_TRUE(shapes_.empty());
  bus_.Publish(channels::kSilhouettes, carved.silhouettes_message);
  ASSERT_TRUE(HandleUntilShapes(1, [&](int64_t now) { shape.Poll(now); }));
  EXPECT_EQ(shapes_[0].trigger_seq, 7);
  EXPECT_TRUE(shapes_[0].valid);
  EXPECT_GT(shapes_[0].centerline_residual_mm, 0.0);  // refined
  EXPECT_EQ(shape.Status(NowUtime()).errors, 0) << shape.Status(NowUtime()).last_error;
}

TEST_F(ShapeServiceTest, SilhouettesThatComeFirstWaitForTheirCloud) {
  ShapeService shape(testing::TestShapeOptions(), rig_->rig(), bus_);
  SubscribeShapes();
  const CarvingOutput carved = Carve(2, 12, NowUtime());
  bus_.Publish(channels::kSilhouettes, carved.silhouettes_message);
  bus_.Publish(channels::kVoxels, carved.message);
  ASSERT_TRUE(HandleUntilShapes(1, [&](int64_t now) { shape.Poll(now); }));
  EXPECT_EQ(shapes_[0].trigger_seq, 12);
  EXPECT_GT(shapes_[0].centerline_residual_mm, 0.0);
  EXPECT_EQ(shape.Status(NowUtime()).errors, 0) << shape.Status(NowUtime()).last_error;
}

TEST_F(ShapeServiceTest, WithoutItsSilhouettesACloudIsMeasuredUnrefinedAfterThePairingTimeout) {
  ShapeServiceOptions options = testing::TestShapeOptions();
  options.pairing_timeout_ms = 50;
  ShapeService shape(options, rig_->rig(), bus_);
  SubscribeShapes();
  bus_.Publish(channels::kVoxels, Carve(1, 8, NowUtime()).message);
  ASSERT_TRUE(HandleUntilShapes(1, [&](int64_t now) { shape.Poll(now); }));
  EXPECT_TRUE(shapes_[0].valid) << shapes_[0].error;
  const service_status_t status = shape.Status(NowUtime());
  EXPECT_EQ(status.errors, 1);
  EXPECT_NE(status.last_error.find("not refined"), std::string::npos) << status.last_error;
}

TEST_F(ShapeServiceTest, WithRefinementOffItNeedsNoSilhouettes) {
  ShapeServiceOptions options = testing::TestShapeOptions();
  options.shape.refine_with_silhouettes = false;
  EXPECT_EQ(options.Validate(), "");
  ShapeService shape(options, rig_->rig(), bus_);
  SubscribeShapes();
  bus_.Publish(channels::kVoxels, Carve(2, 9, NowUtime()).message);
  ASSERT_TRUE(HandleUntilShapes(1, [&](int64_t now) { shape.Poll(now); }));
  EXPECT_TRUE(shapes_[0].valid) << shapes_[0].error;
  EXPECT_EQ(shape.Status(NowUtime()).errors, 0);
}

TEST_F(ShapeServiceTest, MalformedMessagesOnEveryChannelAreCountedAndNeverStopIt) {
  ShapeService shape(testing::TestShapeOptions(), rig_->rig(), bus_);
  SubscribeShapes();
  const int64_t trigger = NowUtime();
  const CarvingOutput carved = Carve(3, 11, trigger);
  const voxel_cloud_t& good = carved.message;
  const std::vector<uint8_t> bytes = Encode(good);
  int rejected = 0;
  // The voxel channel: undecodable ...
  bus_.Publish(channels::kVoxels, shape_t{});
  bus_.Publish(channels::kVoxels, RawBytes{std::vector<uint8_t>(bytes.begin(), bytes.end() - 5)});
  bus_.Publish(channels::kVoxels, RawBytes{std::vector<uint8_t>(64, 0xEE)});
  std::vector<uint8_t> huge = bytes;
  // num_voxels, past the hash, the header and the fixed fields.
  const size_t count =
      8 + static_cast<size_t>(good.header._getEncodedSizeNoHash()) + 8 + 8 + 24 + 8 + 12;
  huge.at(count) = 0x7F;
  bus_.Publish(channels::kVoxels, RawBytes{huge});
  rejected += 4;
  // ... and decodable nonsense, rejected by the worker.
  for (const auto& mutate : std::vector<std::function<void(voxel_cloud_t*)>>{
           [](voxel_cloud_t* m) { m->dims[2] = 0; }, [](voxel_cloud_t* m) { m->voxel_size = 0; },
           [](voxel_cloud_t* m) { m->voxels.back() = 1 << 30; },
           [](voxel_cloud_t* m) { m->voxels[1] = m->voxels[0]; }}) {
    voxel_cloud_t bad = good;
    bad.trigger_seq = 500 + rejected;
    mutate(&bad);
    bus_.Publish(channels::kVoxels, bad);
    ++rejected;
  }
  // The silhouette channel: undecodable, rejected by the bus.
  const std::vector<uint8_t> silhouette_bytes = Encode(carved.silhouettes_message);
  bus_.Publish(channels::kSilhouettes, RawBytes{std::vector<uint8_t>(silhouette_bytes.begin(),
                                                                     silhouette_bytes.end() - 3)});
  bus_.Publish(channels::kSilhouettes, RawBytes{std::vector<uint8_t>(10, 1)});
  rejected += 2;
  // Then the real thing still works.
  bus_.Publish(channels::kSilhouettes, carved.silhouettes_message);
  bus_.Publish(channels::kVoxels, good);
  ASSERT_TRUE(HandleUntil(
      bus_,
      [&] {
        return std::any_of(shapes_.begin(), shapes_.end(),
                           [](const shape_t& s) { return s.trigger_seq == 11; });
      },
      [&](int64_t now) { shape.Poll(now); }));
  ASSERT_TRUE(HandleUntil(
      bus_, [&] { return shape.Status(NowUtime()).rejected >= rejected; },
      [&](int64_t now) { shape.Poll(now); }));
  const service_status_t status = shape.Status(NowUtime());
  EXPECT_EQ(status.rejected, rejected) << status.last_error;
  for (const shape_t& s : shapes_) EXPECT_EQ(s.trigger_seq, 11) << "a malformed cloud was measured";
}

TEST_F(ShapeServiceTest, DecodableButMalformedSilhouettesAreRejectedAndTheCloudMeasuredUnrefined) {
  ShapeServiceOptions options = testing::TestShapeOptions();
  options.pairing_timeout_ms = 50;
  ShapeService shape(options, rig_->rig(), bus_);
  SubscribeShapes();
  CarvingOutput carved = Carve(0, 21, NowUtime());
  carved.silhouettes_message.views[1].mask_end[0] = 30000;  // a run beyond the image
  bus_.Publish(channels::kSilhouettes, carved.silhouettes_message);
  carved.silhouettes_message.views.pop_back();  // a camera short
  carved.silhouettes_message.num_views = 2;
  bus_.Publish(channels::kSilhouettes, carved.silhouettes_message);
  bus_.Publish(channels::kVoxels, carved.message);
  ASSERT_TRUE(HandleUntilShapes(1, [&](int64_t now) { shape.Poll(now); }));
  EXPECT_TRUE(shapes_[0].valid) << shapes_[0].error;
  EXPECT_EQ(shapes_[0].centerline_residual_mm, 0.0);  // not refined
  const service_status_t status = shape.Status(NowUtime());
  EXPECT_EQ(status.rejected, 2);
  EXPECT_EQ(status.errors, 1);  // measured without silhouettes
  EXPECT_NE(status.last_error.find("not refined"), std::string::npos) << status.last_error;
}

TEST(ShapeServiceOptionsTest, ValidationNamesTheKey) {
  ShapeServiceOptions options;
  EXPECT_NE(options.Validate().find("rig"), std::string::npos);
  options.rig = "rig.yaml";
  EXPECT_EQ(options.Validate(), "");
  options.max_waiting = 0;
  EXPECT_NE(options.Validate().find("max_waiting"), std::string::npos);
  options.max_waiting = 8;
  options.pairing_timeout_ms = 0;
  EXPECT_NE(options.Validate().find("pairing_timeout_ms"), std::string::npos);
  options.pairing_timeout_ms = 100;
  options.shape.output_spacing = 5;
  EXPECT_NE(options.Validate().find("shape.output_spacing"), std::string::npos);
}

TEST(ShapeServiceRunTest, StartsAndStopsOnMemq) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("shape_run_test_" + std::to_string(::getpid()));
  TestRig(5).WriteFiles(dir);
  ServiceArgs args;
  args.rig = dir / "rig.yaml";
  args.lcm_url = "memq://";
  args.duration_s = 0.2;
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const service_status_t status = RunShapeService(args, stop, log);
  EXPECT_EQ(status.service, "shape");
  EXPECT_NE(log.str().find("refining"), std::string::npos);
  // It takes no backgrounds, and says so rather than ignore them.
  args.backgrounds = dir / "background";
  try {
    RunShapeService(args, stop, log);
    ADD_FAILURE() << "--backgrounds was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--backgrounds"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace shapesense
