// Frame-set assembly as pure logic with the time passed in: complete sets,
// incomplete ones dropped after the timeout, duplicates, late images and
// unknown cameras rejected, any arrival order, bounded memory.
#include "runtime/lcm/frame_set_assembler.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

namespace shapesense {
namespace {

const std::vector<std::string> kCameras = {"cam0", "cam1", "cam2"};

image_t Image(const std::string& camera, int64_t seq, int64_t trigger_utime = 1'000'000) {
  image_t image{};
  image.camera = camera;
  image.trigger_seq = seq;
  image.trigger_utime = trigger_utime;
  image.host_utime = trigger_utime + 3000;
  image.width = static_cast<int32_t>(seq);  // marks the image, to check where it went
  return image;
}

FrameSetAssemblyOptions Options(double timeout_ms = 100, int max_pending = 4) {
  FrameSetAssemblyOptions options;
  options.timeout_ms = timeout_ms;
  options.max_pending = max_pending;
  return options;
}

// Images that disagree on their trigger (another trigger time for the same
// sequence, or a second, different image of one camera) drop their set:
// nothing proves which image belongs. The same image again is a duplicate.
TEST(FrameSetAssemblerTest, ImagesThatDisagreeOnTheirTriggerDropTheSet) {
  FrameSetAssembler assembler(kCameras, Options());
  ASSERT_EQ(assembler.Add(Image("cam0", 5), 10).outcome, AssemblyOutcome::kPending);
  EXPECT_EQ(assembler.Add(Image("cam1", 5, 1'000'001), 20).outcome, AssemblyOutcome::kConflicting);
  EXPECT_EQ(assembler.pending(), 0u);
  EXPECT_EQ(assembler.Add(Image("cam2", 5), 30).outcome, AssemblyOutcome::kLate);

  image_t first = Image("cam0", 6);
  first.frame_id = 40;
  ASSERT_EQ(assembler.Add(first, 40).outcome, AssemblyOutcome::kPending);
  EXPECT_EQ(assembler.Add(first, 41).outcome, AssemblyOutcome::kDuplicate);
  image_t other = first;
  other.frame_id = 41;
  EXPECT_EQ(assembler.Add(other, 42).outcome, AssemblyOutcome::kConflicting);
  EXPECT_EQ(assembler.counters().conflicting, 2);
  EXPECT_EQ(assembler.counters().DroppedSets(), 2);
  EXPECT_NE(assembler.last_drop().find("disagree"), std::string::npos) << assembler.last_drop();
}

TEST(FrameSetAssemblerTest, ASetCompletesWhenEveryCameraHasAnImageInRigOrder) {
  FrameSetAssembler assembler(kCameras, Options());
  EXPECT_EQ(assembler.Add(Image("cam2", 5), 10).outcome, AssemblyOutcome::kPending);
  EXPECT_EQ(assembler.Add(Image("cam0", 5), 20).outcome, AssemblyOutcome::kPending);
  AssemblyResult result = assembler.Add(Image("cam1", 5), 30);
  ASSERT_EQ(result.outcome, AssemblyOutcome::kCompleted);
  const FrameSet& set = *result.completed;
  EXPECT_EQ(set.trigger_seq, 5);
  EXPECT_EQ(set.trigger_utime, 1'000'000);
  ASSERT_EQ(set.images.size(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(set.images[i].camera, kCameras[i]);
  EXPECT_EQ(set.receive_utime, (std::vector<int64_t>{20, 30, 10}));
  EXPECT_EQ(set.first_receive_utime, 10);
  EXPECT_EQ(set.complete_utime, 30);
  EXPECT_EQ(assembler.pending(), 0u);
  EXPECT_EQ(assembler.counters().completed, 1);
}

TEST(FrameSetAssemblerTest, AnyArrivalOrderGivesEverySetOnceWithItsOwnImages) {
  // Many sets' images shuffled within a window (as several capture hosts
  // interleave them): every set completes exactly once, holding its images.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<image_t> images;
    for (int64_t seq = 0; seq < 30; ++seq) {
      for (const std::string& camera : kCameras) images.push_back(Image(camera, seq));
    }
    for (size_t i = 0; i + 1 < images.size(); ++i) {  // local shuffle: up to 3 sets apart
      std::swap(images[i], images[std::min(images.size() - 1, i + rng() % 9)]);
    }
    FrameSetAssembler assembler(kCameras, Options(1000, 8));
    std::map<int64_t, int> completed;
    int64_t now = 0;
    for (image_t& image : images) {
      AssemblyResult result = assembler.Add(std::move(image), now += 100);
      ASSERT_NE(result.outcome, AssemblyOutcome::kLate);
      if (!result.completed) continue;
      ++completed[result.completed->trigger_seq];
      for (const image_t& member : result.completed->images) {
        EXPECT_EQ(member.width, result.completed->trigger_seq);
      }
    }
    EXPECT_EQ(completed.size(), 30u);
    for (const auto& [seq, count] : completed) EXPECT_EQ(count, 1) << seq;
    EXPECT_EQ(assembler.pending(), 0u);
  }
}

TEST(FrameSetAssemblerTest, IncompleteSetsAreDroppedAfterTheTimeoutAndTheirStragglersAreLate) {
  FrameSetAssembler assembler(kCameras, Options(100));
  assembler.Add(Image("cam0", 1), 0);
  assembler.Add(Image("cam1", 1), 50'000);
  EXPECT_EQ(assembler.Expire(100'000), 0);  // exactly the timeout: still waiting
  EXPECT_EQ(assembler.Expire(100'001), 1);
  EXPECT_EQ(assembler.counters().timed_out, 1);
  EXPECT_NE(assembler.last_drop().find("no image from cam2"), std::string::npos)
      << assembler.last_drop();
  EXPECT_EQ(assembler.Add(Image("cam2", 1), 120'000).outcome, AssemblyOutcome::kLate);
  EXPECT_EQ(assembler.pending(), 0u);
  // Add expires too, before it adds.
  assembler.Add(Image("cam0", 2), 200'000);
  EXPECT_EQ(assembler.Add(Image("cam0", 3), 400'000).outcome, AssemblyOutcome::kPending);
  EXPECT_EQ(assembler.counters().timed_out, 2);
  EXPECT_EQ(assembler.counters().late, 1);
}

TEST(FrameSetAssemblerTest, DuplicatesUnknownCamerasAndLateImagesAreRejectedAndCounted) {
  FrameSetAssembler assembler(kCameras, Options());
  assembler.Add(Image("cam0", 7), 0);
  EXPECT_EQ(assembler.Add(Image("cam0", 7), 1).outcome, AssemblyOutcome::kDuplicate);
  EXPECT_EQ(assembler.Add(Image("cam9", 7), 2).outcome, AssemblyOutcome::kUnknownCamera);
  EXPECT_EQ(assembler.Add(Image("", 7), 2).outcome, AssemblyOutcome::kUnknownCamera);
  assembler.Add(Image("cam1", 7), 3);
  EXPECT_EQ(assembler.Add(Image("cam2", 7), 4).outcome, AssemblyOutcome::kCompleted);
  EXPECT_EQ(assembler.Add(Image("cam2", 7), 5).outcome, AssemblyOutcome::kLate);
  EXPECT_EQ(assembler.counters().duplicates, 1);
  EXPECT_EQ(assembler.counters().unknown_camera, 2);
  EXPECT_EQ(assembler.counters().late, 1);
  EXPECT_EQ(assembler.counters().RejectedImages(), 4);
  EXPECT_EQ(assembler.counters().completed, 1);
}

TEST(FrameSetAssemblerTest, MemoryIsBoundedWhenACameraIsGone) {
  // cam2 is lost: every set stays incomplete. The assembler holds at most
  // max_pending sets, dropping the oldest, and counts every set it drops.
  FrameSetAssembler assembler(kCameras, Options(1e6 / 1e3, 4));
  int64_t now = 0;
  for (int64_t seq = 0; seq < 50; ++seq) {
    assembler.Add(Image("cam0", seq), now += 10);
    assembler.Add(Image("cam1", seq), now += 10);
    EXPECT_LE(assembler.pending(), 4u);
  }
  EXPECT_EQ(assembler.counters().evicted, 46);
  EXPECT_EQ(assembler.counters().DroppedSets() + static_cast<int64_t>(assembler.pending()), 50);
  // cam2 comes back: new sets complete again.
  for (const std::string& camera : kCameras) assembler.Add(Image(camera, 50), now += 10);
  EXPECT_EQ(assembler.counters().completed, 1);
}

TEST(FrameSetAssemblerTest, FreeRunningCamerasAreMatchedByTimeWithinTheTolerance) {
  FrameSetAssemblyOptions options = Options(1000);
  options.time_tolerance_ms = 2.0;
  FrameSetAssembler assembler(kCameras, options);
  // 30 Hz free run: each camera's frames 33.3 ms apart, the cameras up to 1.5 ms apart.
  std::mt19937 rng(5);
  int completed = 0;
  int64_t now = 0;
  for (int frame = 0; frame < 20; ++frame) {
    const int64_t t = 1'000'000 + frame * 33'333;
    std::vector<image_t> images;
    images.reserve(kCameras.size());
    for (const std::string& camera : kCameras) {
      images.push_back(Image(camera, -1, t + static_cast<int64_t>(rng() % 1500)));
    }
    std::shuffle(images.begin(), images.end(), rng);
    for (image_t& image : images) {
      const int64_t time = image.trigger_utime;
      AssemblyResult result = assembler.Add(std::move(image), now += 1000);
      if (!result.completed) continue;
      ++completed;
      EXPECT_EQ(result.completed->trigger_seq, -1);
      EXPECT_LE(t, result.completed->trigger_utime);
      EXPECT_LE(result.completed->trigger_utime, time);
    }
  }
  EXPECT_EQ(completed, 20);
  // An image outside the tolerance of any set starts a new one.
  assembler.Add(Image("cam0", -1, 5'000'000), now += 1000);
  EXPECT_EQ(assembler.Add(Image("cam1", -1, 5'002'500), now += 1000).outcome,
            AssemblyOutcome::kPending);
  EXPECT_EQ(assembler.pending(), 2u);
}

TEST(FrameSetAssemblerTest, FreeRunningImagesWithoutTriggerTimeUseTheHostTime) {
  FrameSetAssembler assembler(kCameras, Options());
  for (const std::string& camera : kCameras) {
    image_t image = Image(camera, -1, 0);
    image.host_utime = 2'000'000 + (camera == "cam1" ? 800 : 0);
    const AssemblyResult result = assembler.Add(image, 10);
    if (camera == "cam2") {
      ASSERT_EQ(result.outcome, AssemblyOutcome::kCompleted);
      EXPECT_EQ(result.completed->trigger_utime, 2'000'000);
    }
  }
}

TEST(FrameSetAssemblerTest, BadConfigurationsAreRefused) {
  EXPECT_THROW(FrameSetAssembler({}, Options()), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler({"cam0", "cam0"}, Options()), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler(kCameras, Options(0)), std::invalid_argument);
  EXPECT_THROW(FrameSetAssembler(kCameras, Options(100, 0)), std::invalid_argument);
  FrameSetAssemblyOptions options;
  options.time_tolerance_ms = -1;
  EXPECT_NE(options.Validate().find("time_tolerance_ms"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
