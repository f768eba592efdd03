// RenderScene and SceneRenderer (declared in tube_scene.h).
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "libs/sim/pixel_noise.h"
#include "libs/sim/ray_table.h"
#include "libs/sim/tube_raster.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {
namespace {

// The tube's coverage of every pixel (0-1) and its shaded colour where it covers.
struct TubeLayer {
  cv::Mat coverage;  // CV_32F
  cv::Mat colour;    // CV_32FC3, BGR
};

cv::Vec3f BaseColour(const RenderOptions& options, const TubeScene& scene, double arc_length) {
  for (const TapeBand& tape : scene.tapes) {
    if (std::abs(arc_length - tape.center_arc_length) <= 0.5 * tape.width) {
      return cv::Vec3f(tape.bgr[0], tape.bgr[1], tape.bgr[2]);
    }
  }
  const auto& body = options.body_bgr;
  return cv::Vec3f(static_cast<float>(body[0]), static_cast<float>(body[1]),
                   static_cast<float>(body[2]));
}

// Lambertian shading; tapes are chosen by the arc length of the closest axis
// point, so their edges are sharp on the tube.
cv::Vec3f ShadedColour(const RenderOptions& options, const TubeScene& scene, const Vec3& light_cam,
                       const SurfacePoint& surface) {
  const double light =
      options.ambient + options.diffuse * std::max(0.0, surface.normal.dot(light_cam));
  return BaseColour(options, scene, surface.arc_length) * static_cast<float>(light);
}

float Coverage(const PixelHit& hit, bool antialias) {
  const bool inside = hit.hit_segment >= 0;
  if (!antialias) return inside ? 1.0f : 0.0f;
  // A straight edge through the pixel covers it in proportion to the centre's
  // signed distance; clamped so the centre's side decides the half.
  const float linear = 0.5f - hit.edge_px;
  return inside ? std::clamp(linear, 0.5f, 1.0f) : std::clamp(linear, 0.0f, 0.5f);
}

TubeLayer ShadeTube(const Camera& camera, const RayTable& rays, const TubeRaster& raster,
                    const TubeAxis& axis, const TubeScene& scene, const RenderOptions& options) {
  Polyline axis_cam;
  axis_cam.reserve(axis.points.size());
  for (const Vec3& p : axis.points) axis_cam.push_back(camera.cam_from_world * p);
  const Vec3 light_cam =
      (camera.cam_from_world.linear() *
       Vec3(options.light_direction[0], options.light_direction[1], options.light_direction[2]))
          .normalized();
  TubeLayer layer{cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0)),
                  cv::Mat(camera.height, camera.width, CV_32FC3, cv::Scalar::all(0))};
  const size_t last = axis_cam.size() - 1;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const PixelHit& hit = raster.at(u, v);
      const float coverage = Coverage(hit, options.antialias);
      if (coverage <= 0.0f) continue;
      const RayTable::Ray& ray = rays.at(u, v);
      const Vec3 direction(ray.x, ray.y, ray.z);
      const bool inside = hit.hit_segment >= 0;
      const size_t i = static_cast<size_t>(inside ? hit.hit_segment : hit.near_segment);
      const size_t j = std::min(i + 1, last);
      const SurfacePoint surface =
          inside ? SurfaceAtDepth(axis_cam[i], axis_cam[j], axis.arc_length[i], axis.arc_length[j],
                                  direction, hit.depth)
                 : SurfaceNearestRay(axis_cam[i], axis_cam[j], axis.arc_length[i],
                                     axis.arc_length[j], direction);
      layer.coverage.at<float>(v, u) = coverage;
      layer.colour.at<cv::Vec3f>(v, u) = ShadedColour(options, scene, light_cam, surface);
    }
  }
  return layer;
}

// Fraction of the backdrop's light left by the shadow: the coverage shifted
// by the offset and blurred (at half resolution: the shadow is soft anyway).
cv::Mat ShadowFactor(const cv::Mat& coverage, const RenderOptions& options) {
  if (options.shadow_strength <= 0.0) return cv::Mat(coverage.size(), CV_32F, cv::Scalar(1.0));
  cv::Mat half;
  cv::resize(coverage, half, cv::Size((coverage.cols + 1) / 2, (coverage.rows + 1) / 2), 0, 0,
             cv::INTER_AREA);
  if (options.shadow_blur_px >= 1.0) {
    cv::GaussianBlur(half, half, cv::Size(0, 0), 0.5 * options.shadow_blur_px);
  }
  // Full-resolution pixel x sees half-resolution (x - offset - 0.5) / 2.
  const double ox = options.shadow_offset_px[0];
  const double oy = options.shadow_offset_px[1];
  const cv::Matx23d full_to_half(0.5, 0.0, -0.5 * ox - 0.25, 0.0, 0.5, -0.5 * oy - 0.25);
  cv::Mat shadow;
  cv::warpAffine(half, shadow, full_to_half, coverage.size(),
                 cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_CONSTANT, cv::Scalar(0));
  return 1.0 - options.shadow_strength * shadow;
}

// Backdrop brightness falls off quadratically from the image centre to the
// corners: 1 - vignette × (column term + row term).
struct Vignette {
  std::vector<float> column;  // per u
  std::vector<float> row;     // per v

  Vignette(const Camera& camera, double vignette) {
    const double cx = 0.5 * (camera.width - 1);
    const double cy = 0.5 * (camera.height - 1);
    const double scale = vignette / (cx * cx + cy * cy);
    for (int u = 0; u < camera.width; ++u)
      column.push_back(static_cast<float>(scale * (u - cx) * (u - cx)));
    for (int v = 0; v < camera.height; ++v)
      row.push_back(static_cast<float>(scale * (v - cy) * (v - cy)));
  }
  float at(int u, int v) const { return 1.0f - column[u] - row[v]; }
};

// The frame (backdrop, shadow, tube) and the background (backdrop alone), each
// with its own noise.
void Compose(const Camera& camera, const TubeLayer& tube, const cv::Mat& shadow,
             const RenderOptions& options, uint64_t seed, RenderedView* view) {
  GaussianNoise image_noise(options.noise_sigma, MixSeed(seed, 0));
  GaussianNoise background_noise(options.noise_sigma, MixSeed(seed, 1));
  const Vignette vignette(camera, options.backdrop_vignette);
  const cv::Vec3f backdrop(static_cast<float>(options.backdrop_bgr[0]),
                           static_cast<float>(options.backdrop_bgr[1]),
                           static_cast<float>(options.backdrop_bgr[2]));
  view->image.create(camera.height, camera.width, CV_8UC3);
  view->background.create(camera.height, camera.width, CV_8UC3);
  for (int v = 0; v < camera.height; ++v) {
    const float* coverage = tube.coverage.ptr<float>(v);
    const cv::Vec3f* colour = tube.colour.ptr<cv::Vec3f>(v);
    const float* light = shadow.ptr<float>(v);
    cv::Vec3b* image = view->image.ptr<cv::Vec3b>(v);
    cv::Vec3b* background = view->background.ptr<cv::Vec3b>(v);
    for (int u = 0; u < camera.width; ++u) {
      const cv::Vec3f lit = backdrop * vignette.at(u, v);
      const cv::Vec3f seen = lit * (light[u] * (1.0f - coverage[u])) + colour[u] * coverage[u];
      for (int c = 0; c < 3; ++c) {
        image[u][c] = cv::saturate_cast<uint8_t>(seen[c] + image_noise.Next());
        background[u][c] = cv::saturate_cast<uint8_t>(lit[c] + background_noise.Next());
      }
    }
  }
}

RenderedView RenderView(const Camera& camera, const RayTable& rays, const TubeAxis& axis,
                        const TubeScene& scene, const RenderOptions& options, uint64_t seed) {
  TubeRaster raster;
  RasterizeTube(camera, rays, axis, &raster);
  const TubeLayer tube = ShadeTube(camera, rays, raster, axis, scene, options);
  RenderedView view;
  Compose(camera, tube, ShadowFactor(tube.coverage, options), options, seed, &view);
  view.truth_mask.create(camera.height, camera.width, CV_8U);
  for (int v = 0; v < camera.height; ++v) {
    uint8_t* mask = view.truth_mask.ptr<uint8_t>(v);
    for (int u = 0; u < camera.width; ++u) mask[u] = raster.at(u, v).hit_segment >= 0 ? 255 : 0;
  }
  return view;
}

void CheckInputs(const TubeScene& scene, const RenderOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("RenderScene: " + error);
  }
  if (scene.centerline.empty() || !(scene.radius > 0.0) || !(scene.lead_in_length >= 0.0)) {
    throw std::invalid_argument(
        "RenderScene: the scene needs a centreline, a positive radius and a lead-in >= 0");
  }
}

}  // namespace

struct SceneRenderer::Impl {
  Rig rig;
  std::vector<RayTable> rays;  // per camera
};

SceneRenderer::SceneRenderer(const Rig& rig) : impl_(std::make_unique<Impl>()) {
  impl_->rig = rig;
  for (const Camera& camera : rig.cameras) impl_->rays.push_back(BuildRayTable(camera));
}

SceneRenderer::~SceneRenderer() = default;
SceneRenderer::SceneRenderer(SceneRenderer&&) noexcept = default;
SceneRenderer& SceneRenderer::operator=(SceneRenderer&&) noexcept = default;

std::vector<RenderedView> SceneRenderer::Render(const TubeScene& scene,
                                                const RenderOptions& options, uint32_t seed) const {
  CheckInputs(scene, options);
  const TubeAxis axis = TubeAxisOf(scene);
  std::vector<RenderedView> views;
  views.reserve(impl_->rig.cameras.size());
  for (size_t i = 0; i < impl_->rig.cameras.size(); ++i) {
    views.push_back(
        RenderView(impl_->rig.cameras[i], impl_->rays[i], axis, scene, options, MixSeed(seed, i)));
  }
  return views;
}

std::vector<RenderedView> RenderScene(const Rig& rig, const TubeScene& scene,
                                      const RenderOptions& options, uint32_t seed) {
  CheckInputs(scene, options);  // before the ray tables are built
  return SceneRenderer(rig).Render(scene, options, seed);
}

}  // namespace shapesense
