// The renderer's looks: shading models, exposure gain and supersampling
// (RenderOptions), and the family of looks built from them (look_family.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>

#include "libs/geometry/polyline.h"
#include "libs/sim/look_family.h"
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

// Hue in degrees (-180 to 180, 0 red, positive towards yellow) and saturation (0-1), HSV.
struct Hsv {
  double hue = 0.0;
  double saturation = 0.0;
};

Hsv HsvOf(double b, double g, double r) {
  const double high = std::max({b, g, r});
  const double spread = high - std::min({b, g, r});
  if (spread <= 0.0) return {};
  double hue = 60.0 * (4.0 + (r - g) / spread);  // blue highest
  if (high == r) hue = 60.0 * (g - b) / spread;
  if (high == g && high != r) hue = 60.0 * (2.0 + (b - r) / spread);
  return {hue > 180.0 ? hue - 360.0 : hue, spread / high};
}

Hsv HsvOf(const std::array<uint8_t, 3>& bgr) { return HsvOf(bgr[0], bgr[1], bgr[2]); }
Hsv HsvOf(const std::array<double, 3>& bgr) { return HsvOf(bgr[0], bgr[1], bgr[2]); }

TEST(LookFamilyTest, HsvOfKnownColours) {
  EXPECT_NEAR(HsvOf(0, 0, 255).hue, 0.0, 1e-9);
  EXPECT_NEAR(HsvOf(0, 255, 255).hue, 60.0, 1e-9);    // yellow
  EXPECT_NEAR(HsvOf(255, 0, 255).hue, -60.0, 1e-9);   // magenta
  EXPECT_NEAR(HsvOf(255, 0, 0).hue, -120.0, 1e-9);    // blue
  EXPECT_NEAR(HsvOf(35, 30, 190).hue, -1.875, 1e-9);  // the independent renderer's tape
  EXPECT_NEAR(HsvOf(100, 100, 200).saturation, 0.5, 1e-9);
  EXPECT_EQ(HsvOf(60, 60, 60).saturation, 0.0);
}

TEST(LookFamilyTest, IsTheSameEveryTimeAndEveryLookValidates) {
  const std::vector<Look> looks = LookFamily();
  const std::vector<Look> again = LookFamily();
  ASSERT_GE(looks.size(), 10u);
  ASSERT_LE(looks.size(), 14u);
  ASSERT_EQ(again.size(), looks.size());
  std::set<std::string> names;
  for (size_t k = 0; k < looks.size(); ++k) {
    EXPECT_EQ(looks[k].render.Validate(), "") << looks[k].name;
    EXPECT_TRUE(names.insert(looks[k].name).second) << "two looks named " << looks[k].name;
    EXPECT_EQ(again[k].name, looks[k].name);
    EXPECT_EQ(again[k].tape_bgr, looks[k].tape_bgr);
    EXPECT_EQ(again[k].render.body_bgr, looks[k].render.body_bgr);
  }
  EXPECT_EQ(looks[0].render.body_bgr, RenderOptions{}.body_bgr) << "the first is the reference";
}

// What the family is for: it must span what issue 16 lists.
TEST(LookFamilyTest, SpansHuesWidthsBodiesShadingExposureAndObliqueness) {
  std::set<std::string> shadings;
  std::set<double> elevations;
  double low_hue = 0.0, high_hue = 0.0, low_gain = 1.0, high_gain = 1.0;
  double narrowest = 100.0, widest = 0.0;
  int pale = 0, supersampled = 0, near_black = 0, light_grey = 0, bluish = 0, dark_red = 0;
  for (const Look& look : LookFamily()) {
    const RenderOptions& render = look.render;
    const Hsv tape = HsvOf(look.tape_bgr);
    low_hue = std::min(low_hue, tape.hue);
    high_hue = std::max(high_hue, tape.hue);
    pale += tape.saturation < 0.55;
    dark_red += look.tape_bgr == std::array<uint8_t, 3>{35, 30, 190};
    narrowest = std::min(narrowest, look.band_width);
    widest = std::max(widest, look.band_width);
    const auto& body = render.body_bgr;
    near_black += *std::max_element(body.begin(), body.end()) < 35.0;
    light_grey += *std::min_element(body.begin(), body.end()) >= 140.0;
    bluish += body[0] > body[2] + 30.0;
    shadings.insert(render.shading);
    low_gain = std::min(low_gain, render.exposure_gain);
    high_gain = std::max(high_gain, render.exposure_gain);
    supersampled += render.supersampling == 3;
    elevations.insert(look.elevation_deg);
    EXPECT_GE(render.noise_sigma, 1.5) << look.name;
    EXPECT_LE(render.noise_sigma, 3.5) << look.name;
  }
  EXPECT_LE(low_hue, -30.0);  // magenta-red
  EXPECT_GE(high_hue, 20.0);  // orange-red
  EXPECT_GE(pale, 2);
  EXPECT_GE(dark_red, 1);
  EXPECT_EQ(narrowest, 3.0);
  EXPECT_EQ(widest, 8.0);
  EXPECT_GE(near_black, 2);
  EXPECT_GE(light_grey, 2);
  EXPECT_GE(bluish, 1);
  EXPECT_EQ(shadings, (std::set<std::string>{"lambert", "phong", "wrap"}));
  EXPECT_GE(low_gain, 0.97);
  EXPECT_LE(low_gain, 0.98);
  EXPECT_LE(high_gain, 1.03);
  EXPECT_GE(high_gain, 1.02);
  EXPECT_GE(supersampled, 3);
  EXPECT_EQ(elevations, (std::set<double>{0.0, 20.0, 40.0, 55.0, 70.0}));
}

// The brightest green a colour reaches under the look's shading and exposure.
double BrightestGreen(const RenderOptions& render, double green) {
  const double highlight = render.shading == "phong" ? 255.0 * render.specular : 0.0;
  return (green * (render.ambient + render.diffuse) + highlight) * render.exposure_gain;
}

// By the numbers, before any rendering: the silhouette's green margin, the
// tape's hue and saturation, and a body the tape classifier cannot take for tape.
TEST(LookFamilyTest, ColoursKeepTheSilhouettesGreenMarginAndTheTapeApart) {
  for (const Look& look : LookFamily()) {
    const RenderOptions& render = look.render;
    const double darkest_backdrop = render.backdrop_bgr[1] * (1.0 - render.backdrop_vignette);
    EXPECT_LE(BrightestGreen(render, look.tape_bgr[1]), darkest_backdrop - 60.0) << look.name;
    EXPECT_LE(BrightestGreen(render, render.body_bgr[1]), darkest_backdrop - 60.0) << look.name;
    const Hsv tape = HsvOf(look.tape_bgr);
    EXPECT_LE(std::abs(tape.hue), 35.0) << look.name;
    EXPECT_GE(tape.saturation, 0.4) << look.name;
    const Hsv body = HsvOf(render.body_bgr);
    EXPECT_TRUE(body.saturation < 0.25 || std::abs(body.hue) >= 90.0)
        << look.name << ": body hue " << body.hue << " saturation " << body.saturation;
  }
}

// Every look rendered once on a synthetic rig at its elevation.
struct LookRender {
  Look look;
  Rig rig;
  TubeScene scene;
  std::vector<RenderedView> views;
};

const std::vector<LookRender>& FamilyRenders() {
  static const std::vector<LookRender> renders = [] {
    std::vector<LookRender> all;
    uint32_t seed = 0;
    for (const Look& look : LookFamily()) {
      SyntheticRigOptions rig_options;
      rig_options.elevation_deg = look.elevation_deg;
      rig_options.seed = seed;
      LookRender render{look, MakeSyntheticRig(rig_options), {}, {}};
      render.scene = RandomScene(render.rig, 100 + seed, 1.5, 3);
      ApplyLook(look, &render.scene);
      render.views = RenderScene(render.rig, render.scene, look.render, seed);
      all.push_back(std::move(render));
      ++seed;
    }
    return all;
  }();
  return renders;
}

TEST(LookFamilyTest, ApplyLookGivesEveryBandTheLooksColourAndWidth) {
  for (const LookRender& render : FamilyRenders()) {
    ASSERT_EQ(render.scene.tapes.size(), 3u);
    for (const TapeBand& tape : render.scene.tapes) {
      EXPECT_EQ(tape.bgr, render.look.tape_bgr);
      EXPECT_EQ(tape.width, render.look.band_width);
    }
  }
}

// The silhouette extractor's test (|green - background green| > 30) finds
// the tube where the truth mask has it, outline pixels included.
TEST(LookFamilyTest, EveryLooksTruthMaskShowsInTheGreenDifference) {
  for (const LookRender& render : FamilyRenders()) {
    for (size_t c = 0; c < render.views.size(); ++c) {
      const RenderedView& view = render.views[c];
      cv::Mat image_green, background_green, difference;
      cv::extractChannel(view.image, image_green, 1);
      cv::extractChannel(view.background, background_green, 1);
      cv::absdiff(image_green, background_green, difference);
      const int tube = cv::countNonZero(view.truth_mask);
      const int found = cv::countNonZero((difference > 30) & view.truth_mask);
      ASSERT_GT(tube, 500) << render.look.name << " camera " << c;
      EXPECT_GE(found, 0.97 * tube)
          << render.look.name << " camera " << c << ": " << found << " of " << tube;
    }
  }
}

// Whether the segment from the camera to `point` passes through the tube
// away from the arc length `s` (another part of the tube hides the point).
bool Hidden(const Vec3& camera, const Vec3& point, const TubeScene& scene, double s) {
  const std::vector<double> arc = CumulativeArcLength(scene.centerline);
  const Vec3 towards = point - camera;
  for (double t = 0.0; t <= arc.back(); t += 0.5) {
    if (std::abs(t - s) < 4.0 * scene.radius) continue;
    const Vec3 p = PointAtArcLength(scene.centerline, arc, t);
    const double along = std::clamp((p - camera).dot(towards) / towards.squaredNorm(), 0.0, 1.0);
    if ((camera + along * towards - p).norm() < scene.radius + 0.3) return true;
  }
  return false;
}

// The surface point of each band's centre that faces a camera shows a
// reddish, saturated colour in every look, shaded, lit, noisy or supersampled.
TEST(LookFamilyTest, EveryLooksTapeCentresAreReddishAndSaturated) {
  for (const LookRender& render : FamilyRenders()) {
    const TubeScene& scene = render.scene;
    const std::vector<double> arc = CumulativeArcLength(scene.centerline);
    int checked = 0, hidden = 0;
    for (size_t c = 0; c < render.views.size(); ++c) {
      const Camera& camera = render.rig.cameras[c];
      for (const TapeBand& tape : scene.tapes) {
        const double s = tape.center_arc_length;
        const Vec3 center = PointAtArcLength(scene.centerline, arc, s);
        const Vec3 tangent = testing::TangentAt(scene.centerline, arc, s);
        Vec3 towards = camera.Center() - center;
        towards = (towards - towards.dot(tangent) * tangent).normalized();
        const Vec3 facing = center + scene.radius * towards;
        if (Hidden(camera.Center(), facing, scene, s)) {
          ++hidden;
          continue;
        }
        const Vec2 pixel = *camera.Project(facing);
        const cv::Vec3b bgr = render.views[c].image.at<cv::Vec3b>(
            static_cast<int>(std::lround(pixel.y())), static_cast<int>(std::lround(pixel.x())));
        const Hsv hsv = HsvOf(bgr[0], bgr[1], bgr[2]);
        EXPECT_LE(std::abs(hsv.hue), 35.0) << render.look.name << " " << camera.name << " " << bgr;
        EXPECT_GE(hsv.saturation, 0.3) << render.look.name << " " << camera.name << " " << bgr;
        ++checked;
      }
    }
    EXPECT_GE(checked, 2 * hidden + 3) << render.look.name;
  }
}

}  // namespace
}  // namespace shapesense
