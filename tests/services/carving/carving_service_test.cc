// The carving service in process over memq://, fed with rendered frame-sets:
// voxel clouds with every stage time, silhouettes for monitoring, status;
// malformed messages counted and survived; overload drops the oldest;
// incomplete sets dropped after the timeout; config loading.
#include "services/carving/carving_service.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <future>
#include <random>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/stage_times.h"
#include "services/shape/shape_service.h"
#include "tests/support/service_test_options.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using testing::Encode;
using testing::HandleUntil;
using testing::RawBytes;
using testing::TestRig;

class CarvingServiceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new TestRig(2); }
  static void TearDownTestSuite() { delete rig_; }

  void Publish(const std::vector<image_t>& images) {
    for (const image_t& image : images) bus_.Publish(channels::Image(image.camera), image);
  }
  void SubscribeVoxels() {
    bus_.Subscribe<voxel_cloud_t>(
        channels::kVoxels,
        [this](const voxel_cloud_t& v, const std::string&, int64_t) { clouds_.push_back(v); });
  }
  // Until `n` clouds arrived and the service counted them (it counts after publishing).
  bool HandleUntilClouds(CarvingService& service, size_t n) {
    return HandleUntil(
        bus_,
        [&] {
          return clouds_.size() >= n &&
                 service.Status(NowUtime()).published >= static_cast<int64_t>(n);
        },
        [&](int64_t now) { service.Poll(now); });
  }

  static TestRig* rig_;
  LcmBus bus_{"memq://"};
  std::vector<voxel_cloud_t> clouds_;
};
TestRig* CarvingServiceTest::rig_ = nullptr;

TEST_F(CarvingServiceTest, PublishesAVoxelCloudPerFrameSetWithEveryStageTime) {
  CarvingServiceOptions options = testing::TestCarvingOptions();
  options.silhouette_rate_hz = 100;  // the first set's silhouettes at least
  CarvingService service(options, rig_->Setup(), bus_);
  SubscribeVoxels();
  std::vector<image_t> silhouettes;
  bus_.Subscribe<image_t>(channels::Silhouette("cam1"), [&](const image_t& s, const std::string&,
                                                            int64_t) { silhouettes.push_back(s); });
  std::vector<service_status_t> statuses;
  bus_.Subscribe<service_status_t>(
      channels::Status("carving"),
      [&](const service_status_t& s, const std::string&, int64_t) { statuses.push_back(s); });
  // Different pixel formats per set: the service decodes them all.
  const int8_t formats[] = {image_t::PIXEL_BGR8, image_t::PIXEL_RGB8, image_t::PIXEL_BAYER_RG8};
  for (int i = 0; i < 3; ++i) Publish(rig_->Messages(i, 10 + i, NowUtime(), formats[i]));
  ASSERT_TRUE(HandleUntilClouds(service, 3));
  HandleUntil(
      bus_, [&] { return !silhouettes.empty() && !statuses.empty(); },
      [&](int64_t now) { service.Poll(now); });

  for (int i = 0; i < 3; ++i) {
    const voxel_cloud_t& cloud = clouds_[static_cast<size_t>(i)];
    EXPECT_EQ(cloud.trigger_seq, 10 + i);
    EXPECT_EQ(cloud.header.seq, i);
    EXPECT_GT(cloud.num_voxels, 100);
    EXPECT_EQ(cloud.voxel_size, testing::kTestVoxelSize);
    for (const char* stage : {"capture", "transport", "silhouette", "carving"}) {
      const stage_time_t* time = FindStageTime(cloud.stage_times, stage);
      ASSERT_NE(time, nullptr) << stage;
      EXPECT_GE(time->duration_us, 0);
      EXPECT_LE(time->end_utime, cloud.header.utime);
    }
  }
  ASSERT_FALSE(silhouettes.empty());
  EXPECT_EQ(silhouettes[0].pixel_format, int8_t{image_t::PIXEL_MONO8});
  EXPECT_EQ(silhouettes[0].trigger_seq, 10);
  cv::Mat mask;
  ASSERT_EQ(ImageMessageToMono(silhouettes[0], &mask), "");
  EXPECT_EQ(mask.cols, rig_->rig().cameras[1].width);
  EXPECT_GT(cv::countNonZero(mask), 500);
  const service_status_t status = service.Status(NowUtime());
  EXPECT_EQ(status.service, "carving");
  EXPECT_EQ(status.received, 9);
  EXPECT_EQ(status.published, 3);
  EXPECT_EQ(status.dropped + status.rejected + status.errors, 0) << status.last_error;
}

TEST_F(CarvingServiceTest, MalformedImagesAreRejectedAndCountedAndNeverStopIt) {
  CarvingService service(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  SubscribeVoxels();
  const std::string channel = channels::Image("cam0");
  const image_t good = rig_->Messages(0, 1, NowUtime())[0];
  const std::vector<uint8_t> bytes = Encode(good);
  // Undecodable: wrong type, truncated, garbage, a count far beyond the buffer.
  bus_.Publish(channel, voxel_cloud_t{});
  bus_.Publish(channel, RawBytes{std::vector<uint8_t>(bytes.begin(), bytes.begin() + 1000)});
  bus_.Publish(channel, RawBytes{std::vector<uint8_t>(300, 0x5A)});
  std::vector<uint8_t> huge_count = bytes;
  // num_stage_times precedes the one stage ("capture": 4 + 8 + 16 bytes) and the pixel count.
  const size_t stage_count = bytes.size() - good.data.size() - 4 - (4 + 8 + 16) - 4;
  for (size_t b = 0; b < 4; ++b) huge_count.at(stage_count + b) = 0x7F;
  bus_.Publish(channel, RawBytes{huge_count});
  // Decodable but malformed: sizes, formats, strides, no camera.
  for (const auto& mutate : std::vector<std::function<void(image_t*)>>{
           [](image_t* m) { m->width = 1000; }, [](image_t* m) { m->pixel_format = 77; },
           [](image_t* m) { m->row_stride = 5; }, [](image_t* m) { m->camera.clear(); },
           [](image_t* m) { m->compression = image_t::COMPRESSION_JPEG; }}) {
    image_t bad = good;
    mutate(&bad);
    bus_.Publish(channel, bad);
  }
  // An unknown camera; a duplicate.
  image_t stranger = good;
  stranger.camera = "cam7";
  bus_.Publish(channels::Image("cam7"), stranger);
  bus_.Publish(channel, good);
  bus_.Publish(channel, good);
  // The rest of set 1 (its cam0 image came above), then another set: both carved.
  const std::vector<image_t> one = rig_->Messages(0, 1, good.trigger_utime);
  bus_.Publish(channels::Image("cam1"), one[1]);
  bus_.Publish(channels::Image("cam2"), one[2]);
  Publish(rig_->Messages(3, 4, NowUtime()));
  ASSERT_TRUE(HandleUntilClouds(service, 2));
  EXPECT_EQ(clouds_[0].trigger_seq, 1);
  EXPECT_EQ(clouds_[1].trigger_seq, 4);
  const service_status_t status = service.Status(NowUtime());
  EXPECT_EQ(status.rejected, 4 + 5 + 2);
  EXPECT_EQ(status.errors, 0) << status.last_error;
  EXPECT_EQ(status.published, 2);
}

TEST_F(CarvingServiceTest, RandomlyCorruptedImagesNeverStopIt) {
  CarvingService service(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  SubscribeVoxels();
  // One byte of a small valid image changed at random, after the type
  // fingerprint: each is rejected, or a valid image of some set (that may
  // even complete and fail in the worker); none stops the service.
  const std::vector<uint8_t> small =
      Encode(testing::MakeImageMessage(cv::Mat(6, 8, CV_8UC3, cv::Scalar(9, 9, 9)), "cam0", 50, 1));
  std::mt19937 rng(9);
  for (int i = 0; i < 300; ++i) {
    std::vector<uint8_t> corrupted = small;
    const size_t at = 8 + rng() % (corrupted.size() - 8);
    corrupted[at] = static_cast<uint8_t>(rng());
    bus_.Publish(channels::Image("cam0"), RawBytes{corrupted});
  }
  // A set no single changed byte can reach (seq 1000 is two bytes from 50).
  Publish(rig_->Messages(0, 1000, NowUtime()));
  ASSERT_TRUE(HandleUntilClouds(service, 1));
  EXPECT_EQ(clouds_.back().trigger_seq, 1000);
  const service_status_t status = service.Status(NowUtime());
  EXPECT_GT(status.rejected, 100);
  EXPECT_EQ(status.received + bus_.Rejected(), 300 + 3);
}

TEST_F(CarvingServiceTest, FrameSetsThatCannotBeCarvedAreCountedAsErrors) {
  CarvingService service(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  SubscribeVoxels();
  // Valid messages that fail only when decoded: a PNG of garbage behind a
  // good signature, and an image of the wrong size for its camera.
  std::vector<image_t> broken = rig_->Messages(1, 2, NowUtime());
  broken[1].compression = image_t::COMPRESSION_PNG;
  broken[1].row_stride = 0;
  broken[1].data.assign(64, 0);
  const uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::copy(std::begin(signature), std::end(signature), broken[1].data.begin());
  broken[1].size = 64;
  Publish(broken);
  std::vector<image_t> wrong_size = rig_->Messages(2, 3, NowUtime());
  const int64_t set_time = wrong_size[2].trigger_utime;
  wrong_size[2] = testing::MakeImageMessage(cv::Mat(100, 120, CV_8UC3, cv::Scalar(1, 2, 3)), "cam2",
                                            3, NowUtime());
  wrong_size[2].trigger_utime = set_time;
  Publish(wrong_size);
  Publish(rig_->Messages(3, 4, NowUtime()));
  ASSERT_TRUE(HandleUntilClouds(service, 1));
  EXPECT_EQ(clouds_[0].trigger_seq, 4);
  const service_status_t status = service.Status(NowUtime());
  EXPECT_EQ(status.errors, 2) << status.last_error;
  EXPECT_EQ(status.rejected, 0);
  EXPECT_EQ(status.published, 1);
}

// The silhouettes are extracted as each image arrives, and found again by
// the image's identity when its set completes: interleaved sets, reversed
// arrival and a duplicate carrying other pixels change nothing, each cloud
// is the one its own set carves to at once.
TEST_F(CarvingServiceTest, SilhouettesExtractedOnArrivalBelongToTheirOwnImages) {
  const CarvingServiceOptions options = testing::TestCarvingOptions();
  CarvingService service(options, rig_->Setup(), bus_);
  SubscribeVoxels();
  const int64_t utime = NowUtime();
  const std::vector<image_t> first = rig_->Messages(0, 20, utime);
  const std::vector<image_t> second = rig_->Messages(1, 21, utime + 10000);
  image_t impostor = rig_->Messages(2, 20, utime)[0];  // the identity of first[0], other pixels
  impostor.frame_id = first[0].frame_id;
  impostor.device_timestamp_ns = first[0].device_timestamp_ns;
  Publish({first[0], impostor, second[2], first[2], second[1], second[0], first[1]});
  ASSERT_TRUE(HandleUntilClouds(service, 2));

  const RigSetup setup = rig_->Setup();
  const CarvingStage stage(setup.rig, setup.backgrounds, options.silhouette, options.carving);
  for (const auto& [images, cloud] :
       {std::pair{&first, &clouds_[1]}, std::pair{&second, &clouds_[0]}}) {
    FrameSet set;
    set.trigger_seq = (*images)[0].trigger_seq;
    set.trigger_utime = (*images)[0].trigger_utime;
    set.images = *images;
    CarvingOutput expected;
    ASSERT_EQ(stage.Process(set, &expected), "");
    EXPECT_EQ(cloud->trigger_seq, set.trigger_seq);
    EXPECT_EQ(cloud->voxels, expected.message.voxels) << "frame-set " << set.trigger_seq;
  }
  const service_status_t status = service.Status(NowUtime());
  EXPECT_EQ(status.rejected, 1) << "the impostor, a duplicate of first[0]";
  EXPECT_EQ(status.errors + status.dropped, 0) << status.last_error;
}

TEST_F(CarvingServiceTest, OverloadDropsTheOldestFrameSetsAndCountsThem) {
  CarvingServiceOptions options = testing::TestCarvingOptions();
  options.queue_capacity = 2;
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  std::atomic<int> carving_calls{0};
  CarvingServiceHooks hooks;
  hooks.before_carving = [&](const FrameSet&) {
    if (carving_calls++ == 0) released.wait();  // hold the worker on the first set
  };
  CarvingService service(options, rig_->Setup(), bus_, hooks);
  SubscribeVoxels();
  const std::vector<image_t> images = rig_->Messages(0, 0, NowUtime());
  auto publish_set = [&](int64_t seq) {
    for (image_t image : images) {
      image.trigger_seq = seq;
      bus_.Publish(channels::Image(image.camera), image);
    }
  };
  publish_set(0);
  ASSERT_TRUE(HandleUntil(bus_, [&] { return carving_calls > 0; }));  // the worker holds set 0
  for (int64_t seq = 1; seq < 8; ++seq) publish_set(seq);
  ASSERT_TRUE(HandleUntil(bus_, [&] { return service.Status(NowUtime()).received == 24; }));
  release.set_value();
  ASSERT_TRUE(HandleUntilClouds(service, 3));
  // The held set, then the two newest; the five between were dropped.
  EXPECT_EQ(clouds_[0].trigger_seq, 0);
  EXPECT_EQ(clouds_[1].trigger_seq, 6);
  EXPECT_EQ(clouds_[2].trigger_seq, 7);
  const service_status_t status = service.Status(NowUtime());
  EXPECT_EQ(status.dropped, 5);
  EXPECT_EQ(status.published, 3);
  EXPECT_NE(status.last_error.find("overload"), std::string::npos) << status.last_error;
}

TEST_F(CarvingServiceTest, AnIncompleteSetIsDroppedAfterTheTimeoutAndReported) {
  CarvingServiceOptions options = testing::TestCarvingOptions();
  options.assembly.timeout_ms = 50;
  CarvingService service(options, rig_->Setup(), bus_);
  SubscribeVoxels();
  std::vector<image_t> images = rig_->Messages(0, 5, NowUtime());
  bus_.Publish(channels::Image("cam0"), images[0]);
  bus_.Publish(channels::Image("cam2"), images[2]);
  ASSERT_TRUE(HandleUntil(
      bus_, [&] { return service.Status(NowUtime()).dropped == 1; },
      [&](int64_t now) { service.Poll(now); }));
  EXPECT_NE(service.Status(NowUtime()).last_error.find("no image from cam1"), std::string::npos);
  // cam1's image arrives late: rejected; the next set is carved.
  bus_.Publish(channels::Image("cam1"), images[1]);
  Publish(rig_->Messages(1, 6, NowUtime()));
  ASSERT_TRUE(HandleUntilClouds(service, 1));
  EXPECT_EQ(clouds_[0].trigger_seq, 6);
  EXPECT_EQ(service.Status(NowUtime()).rejected, 1);
}

class CarvingConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("carving_config_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "data");
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path WriteConfig(const std::string& text) {
    std::ofstream(dir_ / "carving.yaml") << text;
    return dir_ / "carving.yaml";
  }
  fs::path dir_;
};

TEST_F(CarvingConfigTest, RunsFromAConfigWithPathsRelativeToItAndStops) {
  TestRig test_rig(3);
  test_rig.WriteFiles(dir_ / "data");
  ServiceArgs args;
  args.config =
      WriteConfig("rig: data/rig.yaml\nbackgrounds: data/background\ncarving:\n  voxel_size: 4\n");
  args.lcm_url = "memq://";
  args.duration_s = 0.2;
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const service_status_t status = RunCarvingService(args, stop, log);
  EXPECT_EQ(status.service, "carving");
  EXPECT_EQ(status.received, 0);
  EXPECT_NE(log.str().find("3 cameras"), std::string::npos) << log.str();
  // The stop flag ends it too.
  args.duration_s = 0;
  auto running = std::async(std::launch::async, [&] { return RunCarvingService(args, stop, log); });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  stop = true;
  ASSERT_EQ(running.wait_for(std::chrono::seconds(60)), std::future_status::ready);
  running.get();
}

TEST_F(CarvingConfigTest, BadConfigsAreRefusedNamingTheFileAndKeyBeforeLcmStarts) {
  ServiceArgs args;
  args.lcm_url = "udpm://239.255.76.67:7667?ttl=0";  // never opened: the errors come first
  std::atomic<bool> stop{false};
  std::ostringstream log;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"rig: r.yaml\nbackgrounds: b\nqueue_capacity: 0\n", "queue_capacity"},
      {"rig: r.yaml\nbackgrounds: b\ncarving:\n  voxel_size: -1\n", "carving.voxel_size"},
      {"rig: r.yaml\nbackgrounds: b\nassembly:\n  timeout_ms: 0\n", "assembly.timeout_ms"},
      {"rig: r.yaml\nbackgrounds: b\nsilhouete: {}\n", "silhouete"},
      {"backgrounds: b\n", "rig"},
      {"rig: [1, 2\n", "not valid YAML"},
  };
  for (const auto& [text, key] : cases) {
    args.config = WriteConfig(text);
    try {
      RunCarvingService(args, stop, log);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("carving.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  // A missing rig file is named (relative to the config's folder).
  args.config = WriteConfig("rig: missing.yaml\nbackgrounds: b\n");
  EXPECT_THROW(
      {
        try {
          RunCarvingService(args, stop, log);
        } catch (const InputError& e) {
          EXPECT_NE(std::string(e.what()).find((dir_ / "missing.yaml").string()),
                    std::string::npos);
          throw;
        }
      },
      InputError);
  // The command line's rig and backgrounds override the config's.
  args.config = WriteConfig("rig: r.yaml\nbackgrounds: b\n");
  args.rig = dir_ / "other.yaml";
  EXPECT_EQ(LoadCarvingServiceOptions(args).rig, fs::absolute(dir_ / "other.yaml").string());
}

TEST(CarvingShippedConfigTest, TheExampleConfigsLoadWithTheDefaults) {
  ServiceArgs args;
  args.config = fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "carving_service.yaml";
  const CarvingServiceOptions carving = LoadCarvingServiceOptions(args);
  EXPECT_EQ(carving.carving.voxel_size, CarvingOptions{}.voxel_size);
  EXPECT_EQ(carving.queue_capacity, CarvingServiceOptions{}.queue_capacity);
  EXPECT_EQ(fs::path(carving.rig).filename(), "rig.yaml");
  ServiceArgs shape_args;
  shape_args.config = fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "shape_service.yaml";
  const ShapeServiceOptions shape = LoadShapeServiceOptions(shape_args);
  EXPECT_EQ(shape.rig, carving.rig);
  EXPECT_EQ(YAML::Dump(OptionsToYaml(carving.silhouette)),
            YAML::Dump(OptionsToYaml(SilhouetteOptions{})));
}

}  // namespace
}  // namespace shapesense
