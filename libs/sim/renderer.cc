// RenderScene and SceneRenderer (declared in tube_scene.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <mutex>
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

// The options' light in one camera's frame, resolved once per view.
struct Lighting {
  ShadingModel model = ShadingModel::kLambert;
  Vec3 light_cam = Vec3::UnitZ();  // unit, towards the light
};

Lighting LightingOf(const Camera& camera, const RenderOptions& options) {
  const Vec3 light(options.light_direction[0], options.light_direction[1],
                   options.light_direction[2]);
  return {options.shading_model(), (camera.cam_from_world.linear() * light).normalized()};
}

// The diffuse term's share (0-1) at a normal whose cosine to the light is n_dot_l.
double DiffuseShare(const RenderOptions& options, ShadingModel model, double n_dot_l) {
  if (model != ShadingModel::kWrap) return std::max(0.0, n_dot_l);
  return std::max(0.0, (n_dot_l + options.wrap) / (1.0 + options.wrap));
}

// Blinn-Phong highlight in grey levels, white (the light's colour, not the
// surface's), on lit faces only; `direction` is the viewing ray's.
float Highlight(const RenderOptions& options, const Vec3& normal, const Vec3& light,
                const Vec3& direction) {
  const Vec3 halfway = light - direction;
  if (normal.dot(light) <= 0.0 || halfway.norm() < 1e-9) return 0.0f;
  const double cosine = std::max(0.0, normal.dot(halfway.normalized()));
  return static_cast<float>(255.0 * options.specular * std::pow(cosine, options.shininess));
}

// Tapes are chosen by the arc length of the closest axis point, so their
// edges are sharp on the tube (within a pixel, supersampling softens them).
cv::Vec3f ShadedColour(const RenderOptions& options, const TubeScene& scene,
                       const Lighting& lighting, const SurfacePoint& surface,
                       const Vec3& direction) {
  const double n_dot_l = surface.normal.dot(lighting.light_cam);
  const double light =
      options.ambient + options.diffuse * DiffuseShare(options, lighting.model, n_dot_l);
  const cv::Vec3f colour =
      BaseColour(options, scene, surface.arc_length) * static_cast<float>(light);
  if (lighting.model != ShadingModel::kPhong) return colour;
  return colour + cv::Vec3f::all(Highlight(options, surface.normal, lighting.light_cam, direction));
}

float Coverage(const PixelHit& hit, bool antialias) {
  const bool inside = hit.hit_segment >= 0;
  if (!antialias) return inside ? 1.0f : 0.0f;
  // A straight edge through the pixel covers it in proportion to the centre's
  // signed distance; clamped so the centre's side decides the half.
  const float linear = 0.5f - hit.edge_px;
  return inside ? std::clamp(linear, 0.5f, 1.0f) : std::clamp(linear, 0.0f, 0.5f);
}

// The tube's layer over `rect` (image coordinates; the layer's pixel (0, 0)
// is the rect's corner).
TubeLayer ShadeTube(const Camera& camera, const RayTable& rays, const TubeRaster& raster,
                    const TubeAxis& axis, const TubeScene& scene, const RenderOptions& options,
                    const cv::Rect& rect) {
  Polyline axis_cam;
  axis_cam.reserve(axis.points.size());
  for (const Vec3& p : axis.points) axis_cam.push_back(camera.cam_from_world * p);
  const Lighting lighting = LightingOf(camera, options);
  TubeLayer layer{cv::Mat(rect.size(), CV_32F, cv::Scalar(0)),
                  cv::Mat(rect.size(), CV_32FC3, cv::Scalar::all(0))};
  const size_t last = axis_cam.size() - 1;
  for (int v = rect.y; v < rect.y + rect.height; ++v) {
    for (int u = rect.x; u < rect.x + rect.width; ++u) {
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
      layer.coverage.at<float>(v - rect.y, u - rect.x) = coverage;
      layer.colour.at<cv::Vec3f>(v - rect.y, u - rect.x) =
          ShadedColour(options, scene, lighting, surface, direction);
    }
  }
  return layer;
}

// The rays a view's tube is sampled with: the camera's own (one per pixel
// centre), or with supersampling n its sub-pixel camera's (n × n per pixel).
struct Samples {
  const Camera& camera;
  const RayTable& rays;
  int n;
};

// A camera whose pixels are the n × n sub-pixels of `camera`'s: its pixel
// (n u + i, n v + j) is centred on (u + (i + 0.5) / n - 0.5, v + (j + 0.5) / n - 0.5).
Camera SubpixelCamera(const Camera& camera, int n) {
  Camera sub = camera;
  sub.width = n * camera.width;
  sub.height = n * camera.height;
  Mat3 scale;
  scale << n, 0.0, 0.5 * (n - 1), 0.0, n, 0.5 * (n - 1), 0.0, 0.0, 1.0;
  sub.camera_matrix = scale * camera.camera_matrix;
  return sub;
}

// Coverage and coverage-weighted colour summed over the n × n block at (x, y).
void SumBlock(const TubeLayer& fine, int n, int x, int y, float* coverage, cv::Vec3f* weighted) {
  for (int j = 0; j < n; ++j) {
    const float* fine_coverage = fine.coverage.ptr<float>(n * y + j, n * x);
    const cv::Vec3f* fine_colour = fine.colour.ptr<cv::Vec3f>(n * y + j, n * x);
    for (int i = 0; i < n; ++i) {
      *coverage += fine_coverage[i];
      *weighted += fine_colour[i] * fine_coverage[i];
    }
  }
}

// A sub-pixel layer's n × n blocks averaged into pixels: the pixel's coverage
// is its sub-pixels' mean and its colour their coverage-weighted mean, so it
// blends what they show as a camera pixel integrates the light on it.
TubeLayer AverageBlocks(const TubeLayer& fine, int n) {
  const cv::Size size(fine.coverage.cols / n, fine.coverage.rows / n);
  TubeLayer layer{cv::Mat(size, CV_32F, cv::Scalar(0)),
                  cv::Mat(size, CV_32FC3, cv::Scalar::all(0))};
  const auto samples = static_cast<float>(n * n);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      float coverage = 0.0f;
      cv::Vec3f weighted(0.0f, 0.0f, 0.0f);
      SumBlock(fine, n, x, y, &coverage, &weighted);
      if (coverage <= 0.0f) continue;
      layer.coverage.at<float>(y, x) = coverage / samples;
      layer.colour.at<cv::Vec3f>(y, x) = weighted / coverage;
    }
  }
  return layer;
}

// The tube's layer over `rect` (image pixels) from a raster of the samples' rays.
TubeLayer SampledLayer(const Samples& samples, const TubeRaster& raster, const TubeAxis& axis,
                       const TubeScene& scene, const RenderOptions& options, const cv::Rect& rect) {
  if (samples.n == 1) {
    return ShadeTube(samples.camera, samples.rays, raster, axis, scene, options, rect);
  }
  const int n = samples.n;
  const cv::Rect fine(n * rect.x, n * rect.y, n * rect.width, n * rect.height);
  return AverageBlocks(ShadeTube(samples.camera, samples.rays, raster, axis, scene, options, fine),
                       n);
}

// Fraction of the backdrop's light left by the shadow over `out` (image
// coordinates): the coverage shifted by the offset and blurred (at half
// resolution: the shadow is soft anyway). `coverage` covers the image from
// `origin` (even coordinates, even size, so that its half-resolution pixels
// are the whole image's), with zeros around the tube wide enough for the blur.
cv::Mat ShadowFactor(const cv::Mat& coverage, cv::Point origin, const cv::Rect& out,
                     const RenderOptions& options) {
  if (options.shadow_strength <= 0.0) return cv::Mat(out.size(), CV_32F, cv::Scalar(1.0));
  cv::Mat half;
  cv::resize(coverage, half, cv::Size((coverage.cols + 1) / 2, (coverage.rows + 1) / 2), 0, 0,
             cv::INTER_AREA);
  if (options.shadow_blur_px >= 1.0) {
    cv::GaussianBlur(half, half, cv::Size(0, 0), 0.5 * options.shadow_blur_px);
  }
  // Full-resolution pixel x sees half-resolution (x - offset - 0.5) / 2.
  const double ox = options.shadow_offset_px[0];
  const double oy = options.shadow_offset_px[1];
  const cv::Matx23d out_to_half(0.5, 0.0, 0.5 * (out.x - ox - origin.x) - 0.25, 0.0, 0.5,
                                0.5 * (out.y - oy - origin.y) - 0.25);
  cv::Mat shadow;
  cv::warpAffine(half, shadow, out_to_half, out.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_CONSTANT, cv::Scalar(0));
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

cv::Vec3f BackdropBgr(const RenderOptions& options) {
  return {static_cast<float>(options.backdrop_bgr[0]), static_cast<float>(options.backdrop_bgr[1]),
          static_cast<float>(options.backdrop_bgr[2])};
}

// The frame (backdrop, shadow, tube) over `rect` of `image`, exposed by the
// gain, with noise drawn row by row across the rect. `tube` and `shadow`
// cover the rect.
void ComposeImage(const Camera& camera, const TubeLayer& tube, const cv::Mat& shadow,
                  const cv::Rect& rect, const RenderOptions& options, uint64_t seed,
                  cv::Mat* image) {
  GaussianNoise noise(options.noise_sigma, MixSeed(seed, 0));
  const Vignette vignette(camera, options.backdrop_vignette);
  const cv::Vec3f backdrop = BackdropBgr(options);
  const auto gain = static_cast<float>(options.exposure_gain);
  for (int y = 0; y < rect.height; ++y) {
    const int v = rect.y + y;
    const float* coverage = tube.coverage.ptr<float>(y);
    const cv::Vec3f* colour = tube.colour.ptr<cv::Vec3f>(y);
    const float* light = shadow.ptr<float>(y);
    cv::Vec3b* out = image->ptr<cv::Vec3b>(v) + rect.x;
    for (int x = 0; x < rect.width; ++x) {
      const cv::Vec3f lit = backdrop * vignette.at(rect.x + x, v);
      const cv::Vec3f seen =
          (lit * (light[x] * (1.0f - coverage[x])) + colour[x] * coverage[x]) * gain;
      for (int c = 0; c < 3; ++c) out[x][c] = cv::saturate_cast<uint8_t>(seen[c] + noise.Next());
    }
  }
}

// The backdrop alone, with noise of its own (`stream`).
cv::Mat Backdrop(const Camera& camera, const RenderOptions& options, uint64_t seed,
                 uint64_t stream) {
  GaussianNoise noise(options.noise_sigma, MixSeed(seed, stream));
  const Vignette vignette(camera, options.backdrop_vignette);
  const cv::Vec3f backdrop = BackdropBgr(options);
  cv::Mat background(camera.height, camera.width, CV_8UC3);
  for (int v = 0; v < camera.height; ++v) {
    cv::Vec3b* out = background.ptr<cv::Vec3b>(v);
    for (int u = 0; u < camera.width; ++u) {
      const cv::Vec3f lit = backdrop * vignette.at(u, v);
      for (int c = 0; c < 3; ++c) out[u][c] = cv::saturate_cast<uint8_t>(lit[c] + noise.Next());
    }
  }
  return background;
}

// The tube's layer over the whole image. `centres` is the raster of the
// pixel centres, the samples' own when there is one a pixel.
TubeLayer WholeLayer(const Samples& samples, const TubeRaster& centres, const TubeAxis& axis,
                     const TubeScene& scene, const RenderOptions& options, const cv::Rect& whole) {
  if (samples.n == 1) return SampledLayer(samples, centres, axis, scene, options, whole);
  TubeRaster fine;
  RasterizeTube(samples.camera, samples.rays, axis, &fine);
  return SampledLayer(samples, fine, axis, scene, options, whole);
}

RenderedView RenderView(const Samples& centres, const Samples& samples, const TubeAxis& axis,
                        const TubeScene& scene, const RenderOptions& options, uint64_t seed) {
  const Camera& camera = centres.camera;
  TubeRaster raster;
  RasterizeTube(camera, centres.rays, axis, &raster);
  const cv::Rect whole(0, 0, camera.width, camera.height);
  const TubeLayer tube = WholeLayer(samples, raster, axis, scene, options, whole);
  RenderedView view;
  view.image.create(camera.height, camera.width, CV_8UC3);
  ComposeImage(camera, tube, ShadowFactor(tube.coverage, {0, 0}, whole, options), whole, options,
               seed, &view.image);
  view.background = Backdrop(camera, options, seed, 1);
  view.truth_mask.create(camera.height, camera.width, CV_8U);
  for (int v = 0; v < camera.height; ++v) {
    uint8_t* mask = view.truth_mask.ptr<uint8_t>(v);
    for (int u = 0; u < camera.width; ++u) mask[u] = raster.at(u, v).hit_segment >= 0 ? 255 : 0;
  }
  return view;
}

// Pre-rendered noisy backdrops of one camera: the virtual rig's images take
// their backdrop from one of these outside the tube and its shadow.
struct BackdropPool {
  static constexpr size_t kFrames = 8;
  std::array<double, 3> bgr{};
  double vignette = -1.0;
  double noise_sigma = -1.0;
  std::vector<cv::Mat> frames;

  bool Fits(const RenderOptions& options) const {
    return !frames.empty() && bgr == options.backdrop_bgr &&
           vignette == options.backdrop_vignette && noise_sigma == options.noise_sigma;
  }
  void Build(const Camera& camera, const RenderOptions& options) {
    bgr = options.backdrop_bgr;
    vignette = options.backdrop_vignette;
    noise_sigma = options.noise_sigma;
    frames.clear();
    for (size_t k = 0; k < kFrames; ++k) frames.push_back(Backdrop(camera, options, 0x9001, 2 + k));
  }
};

// The image pixels holding the samples the raster may cover (n × n a pixel);
// empty when the tube is out of view.
cv::Rect TubePixels(const TubeRaster& raster, int n) {
  if (raster.u0 > raster.u1) return {};
  return {raster.u0 / n, raster.v0 / n, raster.u1 / n - raster.u0 / n + 1,
          raster.v1 / n - raster.v0 / n + 1};
}

// The pixels the tube and its shadow can change, widened to even coordinates
// (the shadow's half resolution); empty when the tube is out of view.
cv::Rect TubeAndShadowRect(const cv::Rect& tube, const Camera& camera,
                           const RenderOptions& options) {
  if (tube.empty()) return {};
  // The blur's kernel reaches 4 sigma (OpenCV's float kernels), sigma being
  // half the blur at half resolution: 2 blur px at full resolution; 4 px
  // more for the bilinear warp, the area resize and the rounding to even.
  const int margin = static_cast<int>(std::ceil(2.0 * options.shadow_blur_px)) + 4;
  cv::Rect rect(tube.x - margin, tube.y - margin, tube.width + 2 * margin,
                tube.height + 2 * margin);
  if (options.shadow_strength > 0.0) {
    const int ox = static_cast<int>(std::ceil(std::abs(options.shadow_offset_px[0])));
    const int oy = static_cast<int>(std::ceil(std::abs(options.shadow_offset_px[1])));
    rect.x -= ox;
    rect.y -= oy;
    rect.width += 2 * ox;
    rect.height += 2 * oy;
  }
  const int x0 = std::max(0, rect.x) & ~1;
  const int y0 = std::max(0, rect.y) & ~1;
  const int x1 = std::min(camera.width, (rect.x + rect.width + 1) & ~1);
  const int y1 = std::min(camera.height, (rect.y + rect.height + 1) & ~1);
  return {x0, y0, x1 - x0, y1 - y0};
}

// The tube and its shadow drawn over the backdrop in `image` of `camera`,
// sampled by `samples`; `raster` is the samples'.
void DrawTubeOver(const Camera& camera, const Samples& samples, const TubeAxis& axis,
                  const TubeScene& scene, const RenderOptions& options, uint64_t seed,
                  TubeRaster* raster, cv::Mat* image) {
  RasterizeTube(samples.camera, samples.rays, axis, raster);
  const cv::Rect rect = TubeAndShadowRect(TubePixels(*raster, samples.n), camera, options);
  if (rect.empty()) return;
  const TubeLayer tube = SampledLayer(samples, *raster, axis, scene, options, rect);
  ComposeImage(camera, tube, ShadowFactor(tube.coverage, rect.tl(), rect, options), rect, options,
               seed, image);
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

// One camera's sub-pixel camera and its rays.
struct SubpixelRays {
  Camera camera;
  RayTable rays;
};

struct SceneRenderer::Impl {
  Rig rig;
  std::vector<RayTable> rays;  // per camera
  std::mutex pools_mutex;
  std::vector<BackdropPool> pools;  // per camera, built on first use
  std::mutex subpixel_mutex;
  // By camera and supersampling, built on first use and never erased, so
  // references to them stay valid (std::map's nodes do not move).
  std::map<std::pair<size_t, int>, SubpixelRays> subpixel;

  Samples Centres(size_t camera) const { return {rig.cameras[camera], rays[camera], 1}; }

  Samples SamplesOf(size_t camera, int n) {
    if (n == 1) return Centres(camera);
    std::lock_guard lock(subpixel_mutex);
    auto [entry, added] = subpixel.try_emplace({camera, n});
    if (added) {
      entry->second.camera = SubpixelCamera(rig.cameras[camera], n);
      entry->second.rays = BuildRayTable(entry->second.camera);
    }
    return {entry->second.camera, entry->second.rays, n};
  }
};

SceneRenderer::SceneRenderer(const Rig& rig) : impl_(std::make_unique<Impl>()) {
  impl_->rig = rig;
  for (const Camera& camera : rig.cameras) impl_->rays.push_back(BuildRayTable(camera));
  impl_->pools.resize(rig.cameras.size());
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
    views.push_back(RenderView(impl_->Centres(i), impl_->SamplesOf(i, options.supersampling), axis,
                               scene, options, MixSeed(seed, i)));
  }
  return views;
}

cv::Mat SceneRenderer::RenderImage(size_t camera, const TubeScene& scene,
                                   const RenderOptions& options, uint32_t seed) const {
  CheckInputs(scene, options);
  const Camera& model = impl_->rig.cameras.at(camera);
  const Samples samples = impl_->SamplesOf(camera, options.supersampling);
  if (model.width % 2 != 0 || model.height % 2 != 0) {
    return RenderView(impl_->Centres(camera), samples, TubeAxisOf(scene), scene, options,
                      MixSeed(seed, camera))
        .image;
  }
  const uint64_t view_seed = MixSeed(seed, camera);
  cv::Mat image;
  {
    std::lock_guard lock(impl_->pools_mutex);
    BackdropPool& pool = impl_->pools[camera];
    if (!pool.Fits(options)) pool.Build(model, options);
    pool.frames[MixSeed(view_seed, 7) % pool.frames.size()].copyTo(image);
  }
  // The pool is the background's exposure: scaled here, not rebuilt, so an
  // exposure that flickers from image to image costs one pass, not a pool.
  if (options.exposure_gain != 1.0) image.convertTo(image, -1, options.exposure_gain);
  // Reused across calls on this thread: the raster is 16 bytes a sample.
  thread_local TubeRaster raster;
  DrawTubeOver(model, samples, TubeAxisOf(scene), scene, options, view_seed, &raster, &image);
  return image;
}

std::vector<RenderedView> RenderScene(const Rig& rig, const TubeScene& scene,
                                      const RenderOptions& options, uint32_t seed) {
  CheckInputs(scene, options);  // before the ray tables are built
  return SceneRenderer(rig).Render(scene, options, seed);
}

}  // namespace shapesense
