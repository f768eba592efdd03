// The renderer's looks: shading models, exposure gain and supersampling
// (RenderOptions).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"
#include "tests/libs/sim/sim_test_util.h"

namespace shapesense {
namespace {

constexpr double kTubeLength = 160.0;

// A straight tube across camera 0's image (along its x axis), 80 mm either
// side of a point near the workspace centre, no lead-in; arc length s from `start`.
struct StraightTube {
  Rig rig = MakeSyntheticRig({});
  Vec3 across = rig.cameras[0].cam_from_world.linear().row(0).transpose();
  Vec3 start = Vec3(0, 0, 10) - 0.5 * kTubeLength * across;
  TubeScene scene;

  StraightTube() {
    scene.radius = 3.0;
    scene.lead_in_length = 0.0;
    scene.centerline = ArcCenterline(start, across, Vec3::UnitZ(), 0.0, kTubeLength, 0.0);
  }
  const Camera& camera() const { return rig.cameras[0]; }

  // Where the ray through a pixel enters the (infinite) cylinder, as the
  // surface normal and the arc length there; nullopt when it misses.
  std::optional<std::pair<Vec3, double>> Hit(int u, int v) const {
    const Vec3 origin = camera().Center() - start;
    const Vec3 direction = camera().RayDirectionWorld(Vec2(u, v));
    const Vec3 o = origin - origin.dot(across) * across;
    const Vec3 d = direction - direction.dot(across) * across;
    const double a = d.squaredNorm(), b = o.dot(d),
                 c = o.squaredNorm() - scene.radius * scene.radius;
    if (b * b - a * c < 0.0) return std::nullopt;
    const double t = (-b - std::sqrt(b * b - a * c)) / a;
    const Vec3 point = origin + t * direction;
    return std::make_pair(Vec3((o + t * d) / scene.radius), point.dot(across));
  }
};

// Flat backdrop, no noise, no shadow, grey body: what a pixel shows is the
// shading alone.
RenderOptions PlainOptions() {
  RenderOptions options;
  options.backdrop_vignette = 0.0;
  options.noise_sigma = 0.0;
  options.shadow_strength = 0.0;
  options.body_bgr = {200.0, 200.0, 200.0};
  return options;
}

// Interior pixels of a mask: away from its outline, where anti-aliasing blends.
cv::Mat Interior(const cv::Mat& mask, int pixels) {
  cv::Mat interior;
  cv::erode(mask, interior, cv::Mat(), cv::Point(-1, -1), pixels);
  return interior;
}

TEST(RenderLooksTest, DefaultsAreLambertAtUnitGainWithOneRayAPixel) {
  const RenderOptions defaults;
  EXPECT_EQ(defaults.shading, "lambert");
  EXPECT_EQ(defaults.shading_model(), ShadingModel::kLambert);
  EXPECT_EQ(defaults.exposure_gain, 1.0);
  EXPECT_EQ(defaults.supersampling, 1);
  // Explicitly so, with the other models' parameters changed (lambert ignores them).
  RenderOptions explicit_options;
  explicit_options.shading = "lambert";
  explicit_options.exposure_gain = 1.0;
  explicit_options.supersampling = 1;
  explicit_options.wrap = 0.3;
  explicit_options.specular = 0.9;
  explicit_options.shininess = 5.0;
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 4, 1.5);
  const auto expected = RenderScene(rig, scene, defaults, 3);
  const auto views = RenderScene(rig, scene, explicit_options, 3);
  for (size_t i = 0; i < views.size(); ++i) {
    EXPECT_EQ(cv::norm(views[i].image, expected[i].image, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(views[i].background, expected[i].background, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(views[i].truth_mask, expected[i].truth_mask, cv::NORM_INF), 0.0);
  }
}

TEST(RenderLooksTest, ValidateNamesTheBadLookOption) {
  const auto error_of = [](auto change) {
    RenderOptions options;
    change(options);
    return options.Validate();
  };
  EXPECT_NE(error_of([](RenderOptions& o) { o.shading = "toon"; }).find("shading"),
            std::string::npos);
  EXPECT_NE(error_of([](RenderOptions& o) { o.wrap = 1.5; }).find("wrap"), std::string::npos);
  EXPECT_NE(error_of([](RenderOptions& o) { o.specular = -0.1; }).find("specular"),
            std::string::npos);
  EXPECT_NE(error_of([](RenderOptions& o) { o.shininess = 0.5; }).find("shininess"),
            std::string::npos);
  EXPECT_NE(error_of([](RenderOptions& o) { o.exposure_gain = 0.0; }).find("exposure_gain"),
            std::string::npos);
  EXPECT_NE(error_of([](RenderOptions& o) { o.supersampling = 0; }).find("supersampling"),
            std::string::npos);
  EXPECT_EQ(error_of([](RenderOptions& o) { o.shading = "phong"; }), "");
  EXPECT_EQ(error_of([](RenderOptions& o) { o.shading = "wrap"; }).empty(), true);
}

// Every interior pixel of a straight tube against the shading formula
// evaluated on an independent ray-cylinder intersection.
double Expected(const RenderOptions& options, const Vec3& normal, const Vec3& light,
                const Vec3& to_camera) {
  const double n_dot_l = normal.dot(light);
  double diffuse = std::max(0.0, n_dot_l);
  if (options.shading == "wrap")
    diffuse = std::max(0.0, (n_dot_l + options.wrap) / (1 + options.wrap));
  double value = options.body_bgr[1] * (options.ambient + options.diffuse * diffuse);
  if (options.shading == "phong" && n_dot_l > 0.0) {
    const double cosine = std::max(0.0, normal.dot((light + to_camera).normalized()));
    value += 255.0 * options.specular * std::pow(cosine, options.shininess);
  }
  return value;
}

TEST(RenderLooksTest, ShadingModelsFollowTheirFormulas) {
  const StraightTube tube;
  const Camera& camera = tube.camera();
  for (const char* shading : {"lambert", "wrap", "phong"}) {
    RenderOptions options = PlainOptions();
    options.body_bgr = {120.0, 120.0, 120.0};
    options.shading = shading;
    options.wrap = 0.6;
    options.specular = 0.3;
    // Light between the camera and the image's top, so that the highlight
    // and the terminator both show.
    const Vec3 light =
        (camera.cam_from_world.linear().transpose() * Vec3(0.2, -0.8, -0.6)).normalized();
    options.light_direction = {light.x(), light.y(), light.z()};
    const RenderedView view = RenderScene(tube.rig, tube.scene, options, 0)[0];
    const cv::Mat interior = Interior(view.truth_mask, 1);
    int checked = 0;
    for (int v = 0; v < interior.rows; ++v) {
      for (int u = 0; u < interior.cols; ++u) {
        if (!interior.at<uint8_t>(v, u)) continue;
        const auto hit = tube.Hit(u, v);
        ASSERT_TRUE(hit.has_value()) << u << "," << v;
        if (hit->second < 10.0 || hit->second > kTubeLength - 10.0) continue;  // the end caps
        const Vec3 to_camera = -camera.RayDirectionWorld(Vec2(u, v));
        const double expected = Expected(options, hit->first, light, to_camera);
        ASSERT_NEAR(view.image.at<cv::Vec3b>(v, u)[1], std::min(255.0, expected), 1.0)
            << shading << " at " << u << "," << v;
        ++checked;
      }
    }
    EXPECT_GT(checked, 500) << shading;
  }
}

// The soft look: brightness between ambient and ambient + diffuse (75-100 %
// here) over the whole visible tube, the range used, nowhere flat, where
// Lambert with the same light leaves the unlit half flat at the ambient level.
TEST(RenderLooksTest, WrapShadingSpansItsRangeSmoothlyAcrossTheTube) {
  const StraightTube tube;
  RenderOptions options = PlainOptions();
  options.ambient = 0.75;
  options.diffuse = 0.25;
  // From the image's top, square to the line of sight: the visible normals
  // go from facing the light to facing away from it.
  const Vec3 up = -tube.camera().cam_from_world.linear().row(1).transpose();
  options.light_direction = {up.x(), up.y(), up.z()};
  const auto floor_share_and_range = [&](const std::string& shading) {
    options.shading = shading;
    const RenderedView view = RenderScene(tube.rig, tube.scene, options, 0)[0];
    const cv::Mat interior = Interior(view.truth_mask, 1);
    cv::Mat green;
    cv::extractChannel(view.image, green, 1);
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(green, &low, &high, nullptr, nullptr, interior);
    const cv::Mat at_floor = (green <= 150) & interior;
    const double share =
        static_cast<double>(cv::countNonZero(at_floor)) / cv::countNonZero(interior);
    return std::make_tuple(share, low, high);
  };
  const auto [wrap_floor, wrap_low, wrap_high] = floor_share_and_range("wrap");
  EXPECT_GE(wrap_low, 150.0 - 1.0);  // 0.75 × 200
  EXPECT_LE(wrap_high, 200.0 + 1.0);
  EXPECT_GT(wrap_high - wrap_low, 30.0);  // of 50, the interior ending a pixel from the outline
  EXPECT_LT(wrap_floor, 0.02);
  const auto [lambert_floor, lambert_low, lambert_high] = floor_share_and_range("lambert");
  EXPECT_GT(lambert_floor, 0.3);
  EXPECT_GE(lambert_low, 149.0);
}

// A white highlight: phong adds the same to every channel, nothing anywhere
// else than Lambert, and peaks at the strength where the halfway vector
// meets the surface (light from the camera: the line facing the camera).
TEST(RenderLooksTest, PhongAddsAWhiteHighlightToLambert) {
  const StraightTube tube;
  RenderOptions options = PlainOptions();
  options.body_bgr = {40.0, 60.0, 100.0};
  options.specular = 0.3;
  const Vec3 towards_camera = (tube.camera().Center() - Vec3(0, 0, 10)).normalized();
  options.light_direction = {towards_camera.x(), towards_camera.y(), towards_camera.z()};
  const RenderedView lambert = RenderScene(tube.rig, tube.scene, options, 0)[0];
  options.shading = "phong";
  const RenderedView phong = RenderScene(tube.rig, tube.scene, options, 0)[0];
  cv::Mat highlight;
  cv::subtract(phong.image, lambert.image, highlight, cv::noArray(), CV_32FC3);
  const cv::Mat interior = Interior(lambert.truth_mask, 1);
  double peak = 0.0;
  int in_highlight = 0;
  for (int v = 0; v < interior.rows; ++v) {
    for (int u = 0; u < interior.cols; ++u) {
      if (!interior.at<uint8_t>(v, u)) continue;
      const cv::Vec3f added = highlight.at<cv::Vec3f>(v, u);
      EXPECT_GE(added[0], -1.0f);
      EXPECT_NEAR(added[0], added[1], 1.0f);
      EXPECT_NEAR(added[0], added[2], 1.0f);
      peak = std::max(peak, static_cast<double>(added[1]));
      in_highlight += added[1] > 5.0f;
    }
  }
  // Pixel centres sample the narrow peak (exponent 40) within about 0.1 rad.
  EXPECT_GT(peak, 0.8 * 255.0 * options.specular);
  EXPECT_LE(peak, 255.0 * options.specular + 1.0);
  EXPECT_LT(in_highlight, cv::countNonZero(interior) / 2);
  EXPECT_GT(in_highlight, 50);
}

TEST(RenderLooksTest, ExposureGainScalesTheFrameButNotTheBackground) {
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 6, 1.5);
  RenderOptions options;
  options.noise_sigma = 0.0;
  const auto unit = RenderScene(rig, scene, options, 2);
  options.exposure_gain = 0.9;
  const auto dimmer = RenderScene(rig, scene, options, 2);
  for (size_t i = 0; i < unit.size(); ++i) {
    cv::Mat scaled, difference;
    unit[i].image.convertTo(scaled, CV_32FC3, options.exposure_gain);
    cv::subtract(dimmer[i].image, scaled, difference, cv::noArray(), CV_32FC3);
    EXPECT_LE(cv::norm(difference, cv::NORM_INF), 1.0);  // each rounded once
    EXPECT_EQ(cv::norm(dimmer[i].background, unit[i].background, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(dimmer[i].truth_mask, unit[i].truth_mask, cv::NORM_INF), 0.0);
  }
  // With noise too the background frame is the same draw at the same exposure.
  options.noise_sigma = 2.0;
  const auto noisy = RenderScene(rig, scene, options, 2);
  options.exposure_gain = 1.0;
  const auto noisy_unit = RenderScene(rig, scene, options, 2);
  for (size_t i = 0; i < noisy.size(); ++i) {
    EXPECT_EQ(cv::norm(noisy[i].background, noisy_unit[i].background, cv::NORM_INF), 0.0);
    const double ratio = cv::mean(noisy[i].image)[1] / cv::mean(noisy_unit[i].image)[1];
    EXPECT_NEAR(ratio, 0.9, 0.002);
  }
}

// A tape whose near edge crosses a pixel centre: with 3 × 3 rays that pixel
// blends tape and body, with one ray it is one or the other; everywhere
// inside the tube the supersampled colours lie between the two.
TEST(RenderLooksTest, SupersamplingBlendsTheTapeBandsEdges) {
  StraightTube tube;
  const Camera& camera = tube.camera();
  const auto facing_pixel = [&](double s) {
    const Vec3 center = tube.start + s * tube.across;
    Vec3 towards = camera.Center() - center;
    towards = (towards - towards.dot(tube.across) * tube.across).normalized();
    return *camera.Project(center + tube.scene.radius * towards);
  };
  // x grows with s (the tube runs along the image's x): bisect for the edge.
  const double target_u = std::round(facing_pixel(0.5 * kTubeLength).x());
  double low = 0.4 * kTubeLength, high = 0.6 * kTubeLength;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (low + high);
    (facing_pixel(mid).x() < target_u ? low : high) = mid;
  }
  TapeBand tape;
  tape.width = 5.0;
  tape.center_arc_length = low + 0.5 * tape.width;
  tape.bgr = {30, 30, 200};
  tube.scene.tapes = {tape};
  RenderOptions options = PlainOptions();
  options.body_bgr = {60.0, 60.0, 60.0};
  options.ambient = 1.0;
  options.diffuse = 0.0;
  const Vec2 edge = facing_pixel(low);
  const cv::Point straddling(static_cast<int>(target_u), static_cast<int>(std::lround(edge.y())));
  const auto red_at = [&](int supersampling, cv::Mat* image, cv::Mat* interior) {
    options.supersampling = supersampling;
    const RenderedView view = RenderScene(tube.rig, tube.scene, options, 0)[0];
    *image = view.image;
    *interior = Interior(view.truth_mask, 2);
    return view.image.at<cv::Vec3b>(straddling)[2];
  };
  cv::Mat hard, hard_interior, soft, soft_interior;
  const int hard_red = red_at(1, &hard, &hard_interior);
  const int soft_red = red_at(3, &soft, &soft_interior);
  EXPECT_TRUE(hard_red == 60 || hard_red == 200) << hard_red;
  EXPECT_GT(soft_red, 60 + 30);
  EXPECT_LT(soft_red, 200 - 30);
  EXPECT_EQ(cv::norm(hard_interior, soft_interior, cv::NORM_INF), 0.0) << "the same truth mask";
  int hard_blends = 0, soft_blends = 0;
  for (int v = 0; v < soft.rows; ++v) {
    for (int u = 0; u < soft.cols; ++u) {
      if (!soft_interior.at<uint8_t>(v, u)) continue;
      const cv::Vec3b h = hard.at<cv::Vec3b>(v, u), s = soft.at<cv::Vec3b>(v, u);
      hard_blends += h[2] != 60 && h[2] != 200;
      soft_blends += s[2] != 60 && s[2] != 200;
      const double tape_share = (s[2] - 60.0) / 140.0;  // from red; blue and green must agree
      EXPECT_NEAR(s[0], 60.0 - 30.0 * tape_share, 1.0) << u << "," << v;
      EXPECT_EQ(s[0], s[1]);
    }
  }
  EXPECT_EQ(hard_blends, 0);
  EXPECT_GE(soft_blends, 6);  // both edges, across the tube's interior rows
}

// The virtual rig's fast path honours the looks: without noise its images
// are Render()'s to one grey level (the backdrop's exposure is scaled after
// rounding), and the tube's pixels agree exactly.
TEST(RenderLooksTest, RenderImageHonoursGainShadingAndSupersampling) {
  const Rig rig = MakeSyntheticRig({});
  const TubeScene scene = RandomScene(rig, 8, 1.5);
  const SceneRenderer renderer(rig);
  RenderOptions options;
  options.noise_sigma = 0.0;
  options.shading = "phong";
  options.exposure_gain = 1.03;
  options.supersampling = 3;
  const auto exact = renderer.Render(scene, options, 1);
  for (size_t i = 0; i < rig.cameras.size(); ++i) {
    const cv::Mat fast = renderer.RenderImage(i, scene, options, 1);
    EXPECT_LE(cv::norm(fast, exact[i].image, cv::NORM_INF), 1.0) << "camera " << i;
    EXPECT_EQ(cv::norm(fast, exact[i].image, cv::NORM_INF, Interior(exact[i].truth_mask, 1)), 0.0)
        << "camera " << i;
  }
}

}  // namespace
}  // namespace shapesense
