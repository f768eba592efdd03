// The two stages the services and replay share, on rendered frame-sets with
// exact ground truth: voxel cloud and shape with every stage time, and a
// centreline within 1 mm RMS of the truth.
#include "runtime/lcm/pipeline_stages.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "libs/core/error.h"
#include "libs/sim/tube_scene.h"
#include "runtime/lcm/stage_times.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

using testing::TestRig;

FrameSet AssembledSet(const TestRig& test_rig, int scene, int64_t seq, int8_t format) {
  FrameSetAssembler assembler(CameraNames(test_rig.rig()), FrameSetAssemblyOptions{});
  const int64_t now = NowUtime();
  for (image_t& image : test_rig.Messages(scene, seq, now, format)) {
    AssemblyResult result = assembler.Add(std::move(image), now + 100);
    if (result.completed) return *result.completed;
  }
  ADD_FAILURE() << "the set did not complete";
  return {};
}

// The services' tests' voxel size (2 mm: a small table, quick to build
// even under the sanitizers), the other options their defaults.
CarvingOptions TestCarving() {
  CarvingOptions options;
  options.voxel_size = 2.0;
  return options;
}

class PipelineStagesTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { rig_ = new TestRig(1); }
  static void TearDownTestSuite() { delete rig_; }
  static TestRig* rig_;
};
TestRig* PipelineStagesTest::rig_ = nullptr;

TEST_F(PipelineStagesTest, CarvesAndMeasuresWithinAMillimetreWithEveryStageTime) {
  const CarvingStage carving(rig_->rig(), rig_->backgrounds(), SilhouetteOptions{}, TestCarving());
  const ShapeStage shape(rig_->rig(), ShapeOptions{});
  CarvingOutput carved;
  ShapeOutput shaped;
  for (int i = 0; i < 3; ++i) {
    const FrameSet set = AssembledSet(*rig_, i, 100 + i, image_t::PIXEL_BGR8);
    ASSERT_EQ(carving.Process(set, &carved), "");
    EXPECT_EQ(carved.message.trigger_seq, 100 + i);
    EXPECT_EQ(carved.message.trigger_utime, set.trigger_utime);
    EXPECT_GT(carved.message.num_voxels, 100);
    EXPECT_EQ(carved.silhouettes_message.trigger_seq, 100 + i);
    EXPECT_EQ(carved.silhouettes_message.num_views, 3);
    // One datagram: well under 64 kB for three VGA views.
    EXPECT_LT(carved.silhouettes_message.getEncodedSize(), 48'000);
    // Through the wire format, as the shape service receives them.
    SilhouetteSet received;
    ASSERT_EQ(SilhouettesFromMessage(carved.silhouettes_message, rig_->rig(), &received), "");
    EXPECT_EQ(received.trigger_seq, 100 + i);
    ASSERT_EQ(received.views.size(), carved.compact.views.size());
    for (size_t k = 0; k < received.views.size(); ++k) {
      EXPECT_EQ(received.views[k].band_difference, carved.compact.views[k].band_difference);
      EXPECT_EQ(received.views[k].mask.size(), carved.compact.views[k].mask.size());
    }
    ASSERT_EQ(shape.Process(carved.message, &received, &shaped), "");
    EXPECT_EQ(shaped.warning, "");
    EXPECT_GT(shaped.estimate.silhouette_residual_mm, 0.0);  // refined
    ASSERT_TRUE(shaped.estimate.valid) << shaped.estimate.error;
    const GroundTruth truth = TruthOf(rig_->Scene(i));
    const double rms = testing::TwoWayRms(shaped.estimate.centerline, truth.centerline);
    std::printf("scene %d: %d voxels, centreline RMS %.3f mm\n", i, carved.message.num_voxels, rms);
    EXPECT_LT(rms, 1.0);
    for (const char* stage : {"capture", "transport", "silhouette", "carving", "shape"}) {
      EXPECT_NE(FindStageTime(shaped.message.stage_times, stage), nullptr) << stage;
    }
    EXPECT_EQ(shaped.message.num_stage_times, 5);
  }
}

TEST_F(PipelineStagesTest, SilhouettesOfAnotherFrameSetAreNotUsed) {
  const CarvingStage carving(rig_->rig(), rig_->backgrounds(), SilhouetteOptions{}, TestCarving());
  const ShapeStage shape(rig_->rig(), ShapeOptions{});
  CarvingOutput first;
  CarvingOutput second;
  ASSERT_EQ(carving.Process(AssembledSet(*rig_, 0, 1, image_t::PIXEL_BGR8), &first), "");
  ASSERT_EQ(carving.Process(AssembledSet(*rig_, 1, 2, image_t::PIXEL_BGR8), &second), "");
  ShapeOutput shaped;
  ASSERT_EQ(shape.Process(first.message, &second.compact, &shaped), "");
  EXPECT_NE(shaped.warning.find("of another frame-set"), std::string::npos) << shaped.warning;
  EXPECT_EQ(shaped.estimate.silhouette_residual_mm, 0.0);
}

}  // namespace
}  // namespace shapesense
