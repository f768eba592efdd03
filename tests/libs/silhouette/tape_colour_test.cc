#include "libs/silhouette/tape_colour.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {
namespace {

struct TapeView {
  cv::Mat image;
  cv::Mat background;
  cv::Mat tape;  // CV_8U 255: truth tape pixels away from the outline
};

// One camera's view of a random scene whose tapes have colour `bgr`. The
// truth tape pixels are those the tapes change (the scene rendered again
// without them, same seed and noise), away from the outline, where the
// anti-aliased pixels are part backdrop.
TapeView RenderTapeView(const std::array<uint8_t, 3>& bgr, uint32_t seed) {
  SyntheticRigOptions rig_options;
  rig_options.num_cameras = 1;
  rig_options.seed = seed;
  const Rig rig = MakeSyntheticRig(rig_options);
  TubeScene scene = RandomScene(rig, seed, 1.5, 4);
  for (TapeBand& tape : scene.tapes) tape.bgr = bgr;
  TubeScene bare = scene;
  bare.tapes.clear();
  const RenderedView view = RenderScene(rig, scene, RenderOptions{}, seed)[0];
  const RenderedView without = RenderScene(rig, bare, RenderOptions{}, seed)[0];
  cv::Mat difference, changed, interior;
  cv::absdiff(view.image, without.image, difference);
  cv::cvtColor(difference, changed, cv::COLOR_BGR2GRAY);
  cv::erode(view.truth_mask, interior, cv::Mat());
  return {view.image, view.background, (changed > 0) & interior};
}

double TrueHue(const std::array<uint8_t, 3>& bgr) { return HueDeg(bgr.data()); }

// Learnt from one view, labels the tape of another view of another scene.
void ExpectLearntAndLabelled(const std::array<uint8_t, 3>& bgr, const std::string& name) {
  const TapeView calibration = RenderTapeView(bgr, 1);
  const LearntTapeColour learnt =
      LearnTapeColour(calibration.image, calibration.background, SilhouetteOptions{});
  EXPECT_TRUE(learnt.colour.HueInRange(TrueHue(bgr)))
      << name << ": hue " << TrueHue(bgr) << " not in " << Describe(learnt.colour);
  EXPECT_LE(std::abs(std::remainder(learnt.peak_hue_deg - TrueHue(bgr), 360.0)), 2.0) << name;
  EXPECT_GE(learnt.pixels, kMinTapeColourPixels) << name;
  EXPECT_GE(learnt.labelled, learnt.pixels) << name;
  EXPECT_LT(learnt.labelled, learnt.silhouette / 4) << name;
  const TapeView other = RenderTapeView(bgr, 2);
  SilhouetteOptions options;
  options.tape = learnt.colour;
  Silhouette silhouette;
  SilhouetteExtractor(options).Extract(other.image, other.background, &silhouette);
  const cv::Mat marker = silhouette.labels == kLabelMarker;
  const int truth = cv::countNonZero(other.tape);
  ASSERT_GT(truth, 100) << name;
  EXPECT_GE(cv::countNonZero(marker & other.tape), 0.95 * truth)
      << name << " " << Describe(learnt.colour);
}

TEST(LearnTapeColourTest, LearntRangeHoldsTheTapeHueAndLabelsItsPixels) {
  ExpectLearntAndLabelled({35, 30, 190}, "dark red");
  ExpectLearntAndLabelled({20, 70, 230}, "orange-red");
  ExpectLearntAndLabelled({70, 20, 200}, "crimson");
}

std::string LearnError(const cv::Mat& image, const cv::Mat& background,
                       const SilhouetteOptions& options) {
  try {
    LearnTapeColour(image, background, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(LearnTapeColourTest, APriorWindowMatchingNothingIsNamed) {
  const TapeView view = RenderTapeView({30, 30, 200}, 3);
  SilhouetteOptions blue;
  blue.tape.hue_deg = {200.0, 260.0};
  const std::string error = LearnError(view.image, view.background, blue);
  EXPECT_EQ(error.rfind("the tape hue range [200, 260]° (saturation ≥ 0.4, value ≥ 60) matches "
                        "no pixel of the silhouette",
                        0),
            0u)
      << error;
}

TEST(LearnTapeColourTest, NoSilhouetteIsNamed) {
  const TapeView view = RenderTapeView({30, 30, 200}, 3);
  const std::string error = LearnError(view.background, view.background, SilhouetteOptions{});
  EXPECT_EQ(error.rfind("no silhouette:", 0), 0u) << error;
}

TEST(LearnTapeColourTest, TooFewTapePixelsGiveTheCountAndTheMinimum) {
  // A grey bar on the green backdrop with a 6×6 red square inside it.
  const cv::Mat background(120, 160, CV_8UC3, cv::Scalar(40, 175, 45));
  cv::Mat image = background.clone();
  image(cv::Rect(20, 40, 120, 30)).setTo(cv::Scalar(60, 60, 65));
  image(cv::Rect(70, 50, 6, 6)).setTo(cv::Scalar(30, 30, 200));
  const std::string error = LearnError(image, background, SilhouetteOptions{});
  EXPECT_EQ(error.rfind("too few pixels to learn the tape colour from: 36 ", 0), 0u) << error;
  EXPECT_NE(error.find("at least 50 needed"), std::string::npos) << error;
}

TEST(LearnTapeColourTest, ImagesOfAnotherTypeOrSizeAreRejected) {
  const cv::Mat image(48, 64, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(LearnTapeColour(image, cv::Mat(48, 63, CV_8UC3), SilhouetteOptions{}),
               std::invalid_argument);
  EXPECT_THROW(LearnTapeColour(cv::Mat(48, 64, CV_8UC1), image, SilhouetteOptions{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
