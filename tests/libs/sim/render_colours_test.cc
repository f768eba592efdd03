#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "libs/geometry/polyline.h"
#include "libs/silhouette/tape_classifier.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"
#include "tests/libs/sim/sim_test_util.h"

namespace shapesense {
namespace {

// The silhouette extractor's defaults (libs/silhouette) that the colours must suit.
constexpr int kGreenMargin = 60;  // twice its foreground threshold of 30

bool IsRedTape(const cv::Vec3b& bgr) {
  static const TapeClassifier classifier{TapeColour{}};
  return classifier.IsTape(&bgr[0]);
}

// Tape pixels of each view: where the frame changes when the tapes are
// removed (same seed, same noise).
std::vector<cv::Mat> TapePixels(const Rig& rig, const TubeScene& scene,
                                const RenderOptions& options, uint32_t seed,
                                const std::vector<RenderedView>& views) {
  TubeScene bare = scene;
  bare.tapes.clear();
  const auto without = RenderScene(rig, bare, options, seed);
  std::vector<cv::Mat> tapes;
  for (size_t c = 0; c < views.size(); ++c) {
    cv::Mat difference, changed;
    cv::absdiff(views[c].image, without[c].image, difference);
    cv::cvtColor(difference, changed, cv::COLOR_BGR2GRAY);
    tapes.push_back(changed > 0);
  }
  return tapes;
}

TEST(RenderColoursTest, TubeAndTapeSuitTheSilhouetteDefaultsWithMargin) {
  const RenderOptions options;  // defaults, noise included
  for (uint32_t seed = 0; seed < 4; ++seed) {
    SyntheticRigOptions rig_options;
    rig_options.seed = seed;
    const Rig rig = MakeSyntheticRig(rig_options);
    const TubeScene scene = RandomScene(rig, seed, 2.0, 4);
    const auto views = RenderScene(rig, scene, options, seed);
    const std::vector<cv::Mat> tapes = TapePixels(rig, scene, options, seed, views);
    for (size_t c = 0; c < views.size(); ++c) {
      // Away from the outline (anti-aliased pixels blend with the backdrop).
      cv::Mat interior;
      cv::erode(views[c].truth_mask, interior, cv::Mat(), cv::Point(-1, -1), 2);
      const cv::Mat tape = tapes[c] & interior;
      int tape_pixels = 0, body_pixels = 0;
      for (int v = 0; v < interior.rows; ++v) {
        for (int u = 0; u < interior.cols; ++u) {
          if (!interior.at<uint8_t>(v, u)) continue;
          const cv::Vec3b pixel = views[c].image.at<cv::Vec3b>(v, u);
          const int green_difference = views[c].background.at<cv::Vec3b>(v, u)[1] - pixel[1];
          ASSERT_GE(green_difference, kGreenMargin) << "camera " << c << " at " << u << "," << v;
          const bool is_tape = tape.at<uint8_t>(v, u) != 0;
          EXPECT_EQ(IsRedTape(pixel), is_tape) << "camera " << c << " at " << u << "," << v;
          ++(is_tape ? tape_pixels : body_pixels);
        }
      }
      EXPECT_GT(tape_pixels, 30);
      EXPECT_GT(body_pixels, 10 * tape_pixels / 4);
    }
  }
}

TEST(RenderColoursTest, ShadowOnlyDarkensTheBackdropWithoutChangingItsHue) {
  RenderOptions options;
  options.noise_sigma = 0.0;
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 5, 1.0);
  RenderOptions unshadowed = options;
  unshadowed.shadow_strength = 0.0;
  const auto views = RenderScene(rig, scene, options, 0);
  const auto plain = RenderScene(rig, scene, unshadowed, 0);
  for (size_t c = 0; c < views.size(); ++c) {
    const RenderedView& view = views[c];
    cv::Mat near_tube;
    cv::dilate(view.truth_mask, near_tube, cv::Mat(), cv::Point(-1, -1), 2);
    int shadowed = 0;
    Vec2 shadow_centroid = Vec2::Zero(), tube_centroid = Vec2::Zero();
    double shadow_weight = 0.0;
    for (int v = 0; v < view.image.rows; ++v) {
      for (int u = 0; u < view.image.cols; ++u) {
        if (view.truth_mask.at<uint8_t>(v, u)) tube_centroid += Vec2(u, v);
        const cv::Vec3b dark = view.image.at<cv::Vec3b>(v, u);
        const cv::Vec3b lit = view.background.at<cv::Vec3b>(v, u);
        if (near_tube.at<uint8_t>(v, u)) {
          continue;
        }
        // Outside the tube, the frame without the shadow is the background.
        ASSERT_EQ(plain[c].image.at<cv::Vec3b>(v, u), lit);
        if (dark == lit) continue;
        ++shadowed;
        const Vec3 a(dark[0], dark[1], dark[2]), b(lit[0], lit[1], lit[2]);
        EXPECT_LE(a.norm(), b.norm());
        if (b.norm() - a.norm() > 20.0) {  // deep enough that rounding cannot tilt it
          const double angle = std::acos(std::min(1.0, a.dot(b) / (a.norm() * b.norm())));
          EXPECT_LT(angle, 1.5 * M_PI / 180.0) << u << "," << v;
        }
        const double weight = b.norm() - a.norm();
        shadow_centroid += weight * Vec2(u, v);
        shadow_weight += weight;
      }
    }
    ASSERT_GT(shadowed, 100);
    tube_centroid /= cv::countNonZero(view.truth_mask);
    shadow_centroid /= shadow_weight;
    // The shadow falls on the side of the offset (its centroid is biased a
    // little by the part hidden behind the tube).
    const Vec2 offset(options.shadow_offset_px[0], options.shadow_offset_px[1]);
    EXPECT_GT((shadow_centroid - tube_centroid).dot(offset.normalized()), 0.5 * offset.norm());
  }
}

// The surface point of a tape centre that faces a camera shows the tape
// colour; body points between the tapes do not.
TEST(RenderColoursTest, TapeColourAppearsAtTheTapeCentres) {
  for (uint32_t seed = 0; seed < 3; ++seed) {
    const Rig rig = MakeSyntheticRig({});
    const TubeScene scene = RandomScene(rig, seed + 50, 1.5, 3);
    const auto views = RenderScene(rig, scene, {}, seed);
    const std::vector<double> arc = CumulativeArcLength(scene.centerline);
    const Polyline axis = testing::DenseAxis(scene, 0.2);
    for (size_t c = 0; c < views.size(); ++c) {
      const Camera& camera = rig.cameras[c];
      const auto facing_pixel = [&](double s) {
        const Vec3 center = PointAtArcLength(scene.centerline, arc, s);
        const Vec3 tangent = testing::TangentAt(scene.centerline, arc, s);
        Vec3 towards = camera.Center() - center;
        towards = (towards - towards.dot(tangent) * tangent).normalized();
        const Vec2 pixel = *camera.Project(center + scene.radius * towards);
        // Step half a pixel towards the axis so the pixel is not an outline pixel.
        return views[c].image.at<cv::Vec3b>(static_cast<int>(std::lround(pixel.y())),
                                            static_cast<int>(std::lround(pixel.x())));
      };
      for (const TapeBand& tape : scene.tapes) {
        EXPECT_TRUE(IsRedTape(facing_pixel(tape.center_arc_length)))
            << camera.name << " tape at " << tape.center_arc_length;
      }
      for (size_t k = 0; k + 1 < scene.tapes.size(); ++k) {
        const double between =
            0.5 * (scene.tapes[k].center_arc_length + scene.tapes[k + 1].center_arc_length);
        EXPECT_FALSE(IsRedTape(facing_pixel(between))) << camera.name << " body at " << between;
      }
    }
  }
}

}  // namespace
}  // namespace shapesense
