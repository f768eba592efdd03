#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"
#include "tests/libs/sim/sim_test_util.h"

namespace shapesense {
namespace {

struct RenderedScene {
  Rig rig;
  TubeScene scene;
  std::vector<RenderedView> views;
};

RenderedScene RenderRandom(uint32_t seed, double max_bend, const RenderOptions& options = {}) {
  SyntheticRigOptions rig_options;
  rig_options.seed = seed;
  RenderedScene scene_views;
  scene_views.rig = MakeSyntheticRig(rig_options);
  scene_views.scene = RandomScene(scene_views.rig, seed, max_bend);
  scene_views.views = RenderScene(scene_views.rig, scene_views.scene, options, seed);
  return scene_views;
}

TEST(RenderSceneTest, ViewsHaveTheCamerasSizesAndTypes) {
  const RenderedScene scene_views = RenderRandom(1, 1.0);
  ASSERT_EQ(scene_views.views.size(), scene_views.rig.cameras.size());
  for (size_t i = 0; i < scene_views.views.size(); ++i) {
    const Camera& camera = scene_views.rig.cameras[i];
    const RenderedView& view = scene_views.views[i];
    for (const cv::Mat* image : {&view.image, &view.background, &view.truth_mask}) {
      EXPECT_EQ(image->cols, camera.width);
      EXPECT_EQ(image->rows, camera.height);
    }
    EXPECT_EQ(view.image.type(), CV_8UC3);
    EXPECT_EQ(view.background.type(), CV_8UC3);
    EXPECT_EQ(view.truth_mask.type(), CV_8U);
    EXPECT_GT(cv::countNonZero(view.truth_mask), 500);
  }
}

TEST(RenderSceneTest, SurfacePointsProjectInsideTheMask) {
  std::mt19937 rng(3);
  for (uint32_t seed = 0; seed < 3; ++seed) {
    const RenderedScene scene_views = RenderRandom(seed, 2.0);
    const Polyline& line = scene_views.scene.centerline;
    const std::vector<double> arc = CumulativeArcLength(line);
    std::uniform_real_distribution<double> along(0.0, arc.back()), around(0.0, 2 * M_PI);
    for (size_t c = 0; c < scene_views.views.size(); ++c) {
      const Camera& camera = scene_views.rig.cameras[c];
      const cv::Mat& mask = scene_views.views[c].truth_mask;
      for (int k = 0; k < 300; ++k) {
        const double s = along(rng);
        const Vec3 center = PointAtArcLength(line, arc, s);
        const Vec3 normal = testing::PerpendicularAt(testing::TangentAt(line, arc, s), around(rng));
        const Vec2 on_axis = *camera.Project(center);
        const Vec2 on_surface = *camera.Project(center + scene_views.scene.radius * normal);
        // The tube is several pixels wide: the axis is well inside; the surface
        // lies inside or on the outline (1 px allowed).
        EXPECT_TRUE(testing::MaskNear(mask, on_axis, 0)) << camera.name << " s " << s;
        EXPECT_TRUE(testing::MaskNear(mask, on_surface, 1)) << camera.name << " s " << s;
      }
    }
  }
}

TEST(RenderSceneTest, PointsBesideTheTubeProjectOutsideTheMask) {
  std::mt19937 rng(8);
  int checked = 0;
  int occluded = 0;
  for (uint32_t seed = 10; seed < 13; ++seed) {
    const RenderedScene scene_views = RenderRandom(seed, 1.2);
    const Polyline& line = scene_views.scene.centerline;
    const std::vector<double> arc = CumulativeArcLength(line);
    const Polyline axis = testing::DenseAxis(scene_views.scene, 0.1);
    std::uniform_real_distribution<double> middle(0.2 * arc.back(), 0.8 * arc.back());
    for (size_t c = 0; c < scene_views.views.size(); ++c) {
      const Camera& camera = scene_views.rig.cameras[c];
      for (int k = 0; k < 60; ++k) {
        const double s = middle(rng);
        const Vec3 center = PointAtArcLength(line, arc, s);
        // Sideways in the image: perpendicular to the tube and to the line of sight.
        const Vec3 sideways =
            testing::TangentAt(line, arc, s).cross(center - camera.Center()).normalized();
        for (const double side : {-1.5, 1.5}) {
          const Vec2 pixel = *camera.Project(center + side * scene_views.scene.radius * sideways);
          const Vec2 nearest(std::round(pixel.x()), std::round(pixel.y()));
          // Another part of the tube may lie on the same line of sight.
          if (testing::RayDistanceToPoints(camera, nearest, axis) <
              scene_views.scene.radius * 1.05) {
            ++occluded;
            continue;
          }
          ++checked;
          EXPECT_FALSE(testing::MaskNear(scene_views.views[c].truth_mask, pixel, 0))
              << camera.name << " s " << s;
        }
      }
    }
  }
  EXPECT_GT(checked, 20 * occluded);
}

// The mask against an independent, brute-force test of each pixel's ray
// against a dense sampling of the axis (lead-in included), near the outline.
TEST(RenderSceneTest, MaskIsExactlyThePixelsWhoseRayPassesWithinTheRadius) {
  std::mt19937 rng(21);
  for (uint32_t seed = 20; seed < 22; ++seed) {
    const RenderedScene scene_views = RenderRandom(seed, 2.5);
    const Polyline axis = testing::DenseAxis(scene_views.scene, 0.1);
    const double r = scene_views.scene.radius;
    for (size_t c = 0; c < scene_views.views.size(); ++c) {
      const cv::Mat& mask = scene_views.views[c].truth_mask;
      cv::Mat band;  // pixels within 2 px of the outline
      cv::morphologyEx(mask, band, cv::MORPH_GRADIENT,
                       cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
      std::vector<cv::Point> candidates;
      cv::findNonZero(band, candidates);
      std::shuffle(candidates.begin(), candidates.end(), rng);
      int decided = 0;
      for (size_t k = 0; k < std::min<size_t>(candidates.size(), 250); ++k) {
        const cv::Point p = candidates[k];
        const double distance =
            testing::RayDistanceToPoints(scene_views.rig.cameras[c], Vec2(p.x, p.y), axis);
        if (std::abs(distance - r) < 0.005) continue;  // too close to call
        ++decided;
        EXPECT_EQ(mask.at<uint8_t>(p) != 0, distance < r)
            << "camera " << c << " pixel " << p << " distance " << distance << " radius " << r;
      }
      EXPECT_GT(decided, 200);
    }
  }
}

// The mask's area against a dense cloud of surface points splatted into a 4×
// finer grid (an independent estimate of the silhouette's area).
TEST(RenderSceneTest, MaskAreaMatchesADenseSurfaceSplat) {
  const RenderedScene scene_views = RenderRandom(30, 1.5);
  const Polyline axis = testing::DenseAxis(scene_views.scene, 0.08);
  const double r = scene_views.scene.radius;
  constexpr int kScale = 4;
  for (size_t c = 0; c < scene_views.views.size(); ++c) {
    const Camera& camera = scene_views.rig.cameras[c];
    cv::Mat fine(camera.height * kScale, camera.width * kScale, CV_8U, cv::Scalar(0));
    const auto splat = [&](const Vec3& p) {
      const Vec2 pixel = *camera.Project(p);
      const int u = static_cast<int>(std::floor((pixel.x() + 0.5) * kScale));
      const int v = static_cast<int>(std::floor((pixel.y() + 0.5) * kScale));
      if (u >= 0 && v >= 0 && u < fine.cols && v < fine.rows) fine.at<uint8_t>(v, u) = 1;
    };
    // Rings around the axis, and the two end spheres.
    const int ring = static_cast<int>(2 * M_PI * r / 0.08);
    for (size_t i = 0; i + 1 < axis.size(); ++i) {
      const Vec3 tangent = (axis[i + 1] - axis[i]).normalized();
      for (int k = 0; k < ring; ++k)
        splat(axis[i] + r * testing::PerpendicularAt(tangent, 2 * M_PI * k / ring));
    }
    std::mt19937 rng(1);
    for (int k = 0; k < 200000; ++k) {
      const Vec3 n = testing::RandomUnit(rng);
      splat(axis.front() + r * n);
      splat(axis.back() + r * n);
    }
    // The surface's projection covers the silhouette and the points behind fill
    // its interior; the outline's polygon through the centres of the outermost
    // cells encloses the silhouette's area (half the outline cells counted).
    std::vector<std::vector<cv::Point>> outlines;
    cv::findContours(fine, outlines, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    double splat_area = 0.0;
    for (const auto& outline : outlines) splat_area += cv::contourArea(outline);
    splat_area /= kScale * kScale;
    const double mask_area = cv::countNonZero(scene_views.views[c].truth_mask);
    EXPECT_NEAR(mask_area / splat_area, 1.0, 0.02) << camera.name;
  }
}

// Options under which the tube is flat grey and the backdrop flat green, so a
// pixel's green level tells how much of it the tube covers.
RenderOptions FlatOptions() {
  RenderOptions options;
  options.backdrop_vignette = 0.0;
  options.ambient = 1.0;
  options.diffuse = 0.0;
  options.noise_sigma = 0.0;
  options.shadow_strength = 0.0;
  return options;
}

// Along image columns crossing a straight tube, the covered fraction of each
// pixel sums to the tube's width between its exact outlines (found by
// bisection on the camera's own rays), and centres between them.
TEST(RenderSceneTest, AntiAliasingPutsTheOutlineAtItsSubPixelPosition) {
  const Rig rig = MakeSyntheticRig({});
  const Camera& camera = rig.cameras[0];
  const Vec3 across = camera.cam_from_world.linear().row(0).transpose();  // image x in the world
  TubeScene scene;
  scene.radius = 3.0;
  scene.lead_in_length = 0.0;
  const Vec3 start = Vec3(0, 0, 10) - 80.0 * across;
  scene.centerline = ArcCenterline(start, across, Vec3::UnitZ(), 0.0, 160.0, 0.0);
  const RenderOptions options = FlatOptions();
  const cv::Mat image = RenderScene(rig, scene, options, 1)[0].image;
  const double backdrop = options.backdrop_bgr[1];
  const double body = options.body_bgr[1];
  const auto distance = [&](double u, double v) {
    const Vec3 d = camera.RayDirectionWorld(Vec2(u, v));
    const Vec3 w = camera.Center() - start;
    const Vec3 n = d.cross(across).normalized();
    return std::abs(w.dot(n)) - scene.radius;  // ray to the (infinite) axis line
  };
  const auto outline = [&](double u, double inside, double outside) {
    for (int k = 0; k < 60; ++k) {
      const double mid = 0.5 * (inside + outside);
      (distance(u, mid) < 0.0 ? inside : outside) = mid;
    }
    return inside;
  };
  const Vec2 middle = *camera.Project(start + 80.0 * across);
  for (int u = static_cast<int>(middle.x()) - 80; u <= middle.x() + 80; u += 4) {
    // The axis's image in this column: where the ray's distance to it is least.
    double low = middle.y() - 20.0, high = middle.y() + 20.0;
    for (int k = 0; k < 100; ++k) {
      const double a = low + (high - low) / 3.0, b = high - (high - low) / 3.0;
      (distance(u, a) < distance(u, b) ? high : low) = distance(u, a) < distance(u, b) ? b : a;
    }
    const double center_v = 0.5 * (low + high);
    const double top = outline(u, center_v, center_v - 30.0);
    const double bottom = outline(u, center_v, center_v + 30.0);
    double sum = 0.0;
    double moment = 0.0;
    for (int v = static_cast<int>(top) - 3; v <= bottom + 3; ++v) {
      const double coverage = (backdrop - image.at<cv::Vec3b>(v, u)[1]) / (backdrop - body);
      sum += coverage;
      moment += coverage * v;
    }
    EXPECT_NEAR(sum, bottom - top, 0.03) << "column " << u;
    EXPECT_NEAR(moment / sum, 0.5 * (top + bottom), 0.03) << "column " << u;
  }
}

TEST(RenderSceneTest, ImageEqualsTheBackgroundAwayFromTheTubeAndItsShadow) {
  const RenderOptions options;
  const RenderedScene scene_views = RenderRandom(40, 1.5, options);
  for (const RenderedView& view : scene_views.views) {
    cv::Mat shifted;
    const cv::Matx23d shift(1, 0, options.shadow_offset_px[0], 0, 1, options.shadow_offset_px[1]);
    cv::warpAffine(view.truth_mask, shifted, shift, view.truth_mask.size());
    cv::Mat near = view.truth_mask | shifted;
    const int reach = static_cast<int>(4 * options.shadow_blur_px) + 4;
    cv::dilate(
        near, near,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * reach + 1, 2 * reach + 1)));
    cv::Mat difference;
    cv::subtract(view.image, view.background, difference, cv::noArray(), CV_32FC3);
    cv::Scalar mean, deviation;
    cv::meanStdDev(difference, mean, deviation, ~near);
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(difference.reshape(1), &low, &high);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(mean[c], 0.0, 0.05);
      // Two independent noise draws: the difference has √2 times their spread.
      EXPECT_NEAR(deviation[c], std::sqrt(2.0) * options.noise_sigma, 0.1 * options.noise_sigma);
    }
    cv::Mat far_difference;
    difference.copyTo(far_difference, ~near);
    cv::minMaxLoc(far_difference.reshape(1), &low, &high);
    EXPECT_LE(std::max(-low, high), 8.0 * options.noise_sigma);
  }
}

TEST(RenderSceneTest, SameSeedSameImagesOtherSeedOtherNoise) {
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 2, 1.0);
  const RenderOptions options;
  const auto first = RenderScene(rig, scene, options, 7);
  const auto again = RenderScene(rig, scene, options, 7);
  const auto other = RenderScene(rig, scene, options, 8);
  for (size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(cv::norm(first[i].image, again[i].image, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(first[i].background, again[i].background, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(first[i].truth_mask, other[i].truth_mask, cv::NORM_INF), 0.0);
    EXPECT_GT(cv::norm(first[i].image, other[i].image, cv::NORM_L1), first[i].image.total() * 1.0);
    EXPECT_GT(cv::norm(first[i].background, other[i].background, cv::NORM_L1),
              first[i].image.total() * 1.0);
    // The frame and its background carry different noise draws.
    cv::Mat a, b;
    first[i].image.row(0).convertTo(a, CV_32F);
    first[i].background.row(0).convertTo(b, CV_32F);
    EXPECT_GT(cv::norm(a, b, cv::NORM_L1), 0.5 * a.total());
  }
  // Views of different cameras do not share a noise draw either.
  cv::Mat a, b;
  cv::subtract(first[0].background, first[1].background, a, cv::noArray(), CV_32FC3);
  EXPECT_GT(cv::norm(a, cv::NORM_L1), 0.0);
}

TEST(RenderSceneTest, RejectsInvalidOptionsAndScenes) {
  EXPECT_EQ(RenderOptions{}.Validate(), "");
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 1, 1.0);
  RenderOptions options;
  options.shadow_strength = 1.5;
  EXPECT_NE(options.Validate().find("shadow_strength"), std::string::npos);
  EXPECT_THROW(RenderScene(rig, scene, options, 0), std::invalid_argument);
  options = {};
  options.body_bgr = {0, 300, 0};
  EXPECT_NE(options.Validate().find("body_bgr"), std::string::npos);
  options = {};
  options.light_direction = {0, 0, 0};
  EXPECT_NE(options.Validate().find("light_direction"), std::string::npos);
  TubeScene bad = scene;
  bad.radius = 0.0;
  EXPECT_THROW(RenderScene(rig, bad, {}, 0), std::invalid_argument);
}

TEST(SceneRendererTest, GivesTheSameImagesAsRenderSceneSceneAfterScene) {
  const Rig rig = MakeSyntheticRig({});
  const SceneRenderer renderer(rig);
  for (uint32_t seed = 0; seed < 2; ++seed) {
    const TubeScene scene = RandomScene(rig, seed, 1.5);
    const auto expected = RenderScene(rig, scene, {}, seed);
    const auto views = renderer.Render(scene, {}, seed);
    ASSERT_EQ(views.size(), expected.size());
    for (size_t i = 0; i < views.size(); ++i) {
      EXPECT_EQ(cv::norm(views[i].image, expected[i].image, cv::NORM_INF), 0.0);
      EXPECT_EQ(cv::norm(views[i].background, expected[i].background, cv::NORM_INF), 0.0);
      EXPECT_EQ(cv::norm(views[i].truth_mask, expected[i].truth_mask, cv::NORM_INF), 0.0);
    }
  }
}

}  // namespace
}  // namespace shapesense

namespace shapesense {
namespace {

// The virtual rig's renderer draws the exact renderer's tube and shadow:
// without noise its images are Render()'s, over many scenes, bends and
// shadow settings (the tube near the image's edges too), but for a few
// shadow pixels one grey level off (the shadow's warp over a smaller
// region rounds its fixed-point sampling positions differently).
TEST(RenderImageTest, WithoutNoiseEqualsTheExactRendererToOneGreyLevel) {
  for (uint32_t seed = 0; seed < 12; ++seed) {
    RenderOptions options;
    options.noise_sigma = 0.0;
    options.shadow_blur_px = 2.0 + seed % 4 * 3.0;
    options.shadow_offset_px = {-10.0 + seed * 2.0, 12.0 - seed * 1.5};
    if (seed % 5 == 4) options.shadow_strength = 0.0;
    SyntheticRigOptions rig_options;
    rig_options.seed = seed;
    const Rig rig = MakeSyntheticRig(rig_options);
    const TubeScene scene = RandomScene(rig, 100 + seed, 2.5);
    const SceneRenderer renderer(rig);
    const std::vector<RenderedView> exact = renderer.Render(scene, options, seed);
    for (size_t i = 0; i < rig.cameras.size(); ++i) {
      const cv::Mat fast = renderer.RenderImage(i, scene, options, seed);
      EXPECT_LE(cv::norm(fast, exact[i].image, cv::NORM_INF), 1.0)
          << "seed " << seed << " camera " << i;
      cv::Mat differs;
      cv::compare(fast.reshape(1), exact[i].image.reshape(1), differs, cv::CMP_NE);
      EXPECT_LE(cv::countNonZero(differs), static_cast<int>(fast.total() / 1000))
          << "seed " << seed << " camera " << i;
    }
  }
}

// With noise, the images differ from the exact renderer's by two noise
// draws at most, with the noise's spread; consecutive images differ.
TEST(RenderImageTest, WithNoiseDiffersFromTheExactRendererOnlyByNoise) {
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 3, 1.5);
  const SceneRenderer renderer(rig);
  const RenderOptions options;
  const std::vector<RenderedView> exact = renderer.Render(scene, options, 5);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const cv::Mat fast = renderer.RenderImage(i, scene, options, 5);
    cv::Mat difference;
    cv::subtract(fast, exact[i].image, difference, cv::noArray(), CV_32FC3);
    cv::Scalar mean, deviation;
    cv::meanStdDev(difference, mean, deviation);
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(mean[c], 0.0, 0.05);
      EXPECT_NEAR(deviation[c], std::sqrt(2.0) * options.noise_sigma, 0.1 * options.noise_sigma);
    }
    const cv::Mat next = renderer.RenderImage(i, scene, options, 6);
    EXPECT_GT(cv::norm(fast, next, cv::NORM_L1), fast.total() * 1.0) << "new noise per image";
  }
}

}  // namespace
}  // namespace shapesense
