#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"

namespace shapesense {

// A band of coloured tape around the tube.
struct TapeBand {
  double center_arc_length = 0.0;  // from the base, mm
  double width = 4.0;              // along the tube, mm
  std::array<uint8_t, 3> bgr = {30, 30, 200};
};

// A tube of constant radius swept along a centreline, with a hemispherical
// tip. The centreline starts at the base (where the manipulator enters the
// workspace); a straight lead-in behind the base is drawn but is not part of
// the measured body (it stands for the sheath or mount the tube comes from).
struct TubeScene {
  Polyline centerline;           // base → tip, world frame, mm; sampled finely (≤ 0.5 mm)
  double radius = 3.0;           // mm
  double lead_in_length = 40.0;  // mm, straight, behind the base
  std::vector<TapeBand> tapes;
  // The manipulator's configuration when the scene was made from one
  // (manipulator_scene.h); the renderer ignores it, TruthOf passes it on.
  std::optional<Configuration> configuration;
};

// What the cameras should measure.
struct GroundTruth {
  Polyline centerline;        // as in the scene, base → tip
  Vec3 tip = Vec3::Zero();    // distal end of the centreline (centre of the hemispherical tip)
  double length = 0.0;        // mm
  std::vector<Vec3> markers;  // tape centres on the centreline, base → tip
  std::vector<double> marker_arc_length;
  std::optional<Configuration> configuration;  // the scene's, when it has one
};

GroundTruth TruthOf(const TubeScene& scene);

// How body and tapes are shaded (RenderOptions::shading).
enum class ShadingModel { kLambert, kWrap, kPhong };

// How the scene looks. The tube is the union of capsules (sphere-swept
// segments) around the lead-in and the centreline, ray-cast exactly per pixel
// centre (or per sub-pixel, `supersampling`) through the lens model. The
// default colours suit the silhouette extractor's defaults with margin: the
// body's and the tapes' green stay at least 75 grey levels below the
// (vignetted) backdrop's under any shading; the tapes pass its tape colour
// test (hue 335-25°, saturation ≥ 0.4, value ≥ 60) everywhere; the shadow
// only scales the backdrop's colour, so its hue does not change.
struct RenderOptions {
  std::array<double, 3> backdrop_bgr = {40.0, 175.0, 45.0};
  // Brightness falls off from the image centre to the corners by this fraction.
  double backdrop_vignette = 0.15;
  // The tube between tapes (the tapes carry their own colour).
  std::array<double, 3> body_bgr = {60.0, 60.0, 65.0};
  // Shading of body and tapes, with a light from this direction (world):
  //  lambert: colour × (ambient + diffuse × max(0, n·l));
  //  wrap:    colour × (ambient + diffuse × max(0, (n·l + wrap) / (1 + wrap))), a
  //           diffuse term wrapped past the terminator (wrap 1: linear
  //           half-Lambert), so the brightness falls smoothly from ambient +
  //           diffuse to ambient over the whole tube instead of going flat on its
  //           unlit half: soft shading such as 75-100 % across the tube;
  //  phong:   lambert plus a white Blinn-Phong highlight, specular × 255 ×
  //           max(0, n·h)^shininess grey levels on every channel where n·l > 0
  //           (h halfway between the light and the camera).
  // The defaults (lambert) give the images made before the other models existed.
  std::string shading = "lambert";
  std::array<double, 3> light_direction = {0.3, -0.5, 1.0};
  double ambient = 0.55;
  double diffuse = 0.6;
  double wrap = 1.0;        // wrap only
  double specular = 0.15;   // phong only: highlight peak, fraction of full scale
  double shininess = 40.0;  // phong only: Blinn-Phong exponent
  // Exposure of this frame over the background frame's: the frame (tube and
  // backdrop) is scaled by it before the noise, the background frame is not,
  // as a camera's exposure flicker between the background shot and a live frame.
  double exposure_gain = 1.0;
  // Rays per pixel: n × n, on a regular sub-pixel grid, averaged (the tube's
  // coverage and its coverage-weighted colour), which anti-aliases every edge
  // of the tube including its tape bands' (1: one ray through the pixel
  // centre, tape edges hard). Costs about n² times the tube's work and keeps
  // the sub-pixel rays of each camera (16 bytes each) for the renderer's life.
  // The truth mask stays the pixel centres' either way.
  int supersampling = 1;
  // Gaussian pixel noise, grey levels (standard deviation), drawn per channel,
  // independently for the frame and for the background.
  double noise_sigma = 2.0;
  // Soft shadow of the tube on the backdrop (not on the tube): the backdrop is
  // scaled by 1 - strength × the tube's coverage shifted by the offset (px)
  // and blurred by a Gaussian of this standard deviation (px).
  double shadow_strength = 0.35;
  std::array<double, 2> shadow_offset_px = {14.0, 10.0};
  double shadow_blur_px = 6.0;
  // Anti-aliasing: a pixel near the outline is covered in proportion to its
  // area on the tube's side of a straight outline at the exact sub-pixel
  // position (from the ray's distance to the axis), and blends the shaded tube
  // with the backdrop accordingly. Off: each pixel is tube or backdrop by its centre.
  bool antialias = true;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("backdrop_bgr", backdrop_bgr, "backdrop colour, BGR 0-255");
    visit("backdrop_vignette", backdrop_vignette, "brightness fall-off to the corners (0-1)");
    visit("body_bgr", body_bgr, "tube colour, BGR 0-255");
    visit("shading", shading, "lambert | wrap | phong");
    visit("light_direction", light_direction, "direction towards the light, world frame");
    visit("ambient", ambient, "ambient light (0-2)");
    visit("diffuse", diffuse, "diffuse light (0-2)");
    visit("wrap", wrap, "wrap shading: how far the diffuse light wraps past the terminator (0-1)");
    visit("specular", specular, "phong shading: highlight peak, fraction of 255 (0-1)");
    visit("shininess", shininess, "phong shading: Blinn-Phong exponent (1-1000)");
    visit("exposure_gain", exposure_gain,
          "frame brightness over the background frame's, exposure flicker (0.5-2)");
    visit("supersampling", supersampling, "n x n rays per pixel, averaged (1-4; 1: off)");
    visit("noise_sigma", noise_sigma, "pixel noise, grey levels");
    visit("shadow_strength", shadow_strength, "shadow darkening (0: none, < 1)");
    visit("shadow_offset_px", shadow_offset_px, "shadow offset in the image, px");
    visit("shadow_blur_px", shadow_blur_px, "shadow blur, px");
    visit("antialias", antialias, "anti-aliased edges");
  }
  std::string Validate() const;
  ShadingModel shading_model() const;  // of a validated `shading`
};

// One camera's rendering: the frame, a background frame (backdrop alone, its
// own noise, no tube, no shadow), and the exact mask of the tube (the measured
// body and the lead-in): a pixel is in it when the ray through its centre
// meets the tube.
struct RenderedView {
  cv::Mat image;       // CV_8UC3 BGR
  cv::Mat background;  // CV_8UC3 BGR
  cv::Mat truth_mask;  // CV_8U, 255 where the tube covers the pixel centre
};

// Renders the scene into every camera of the rig (in rig order), with lens
// distortion. Deterministic for a given seed. Throws std::invalid_argument on
// options that fail Validate() or a scene without centreline or radius.
std::vector<RenderedView> RenderScene(const Rig& rig, const TubeScene& scene,
                                      const RenderOptions& options, uint32_t seed);

// Renders scene after scene for one rig, keeping between calls what depends on
// the cameras alone (every pixel's viewing ray, about a third of the work).
// RenderScene is a SceneRenderer used once; both give identical images.
// Render() may be called from several threads at once.
class SceneRenderer {
 public:
  explicit SceneRenderer(const Rig& rig);
  ~SceneRenderer();
  SceneRenderer(SceneRenderer&&) noexcept;
  SceneRenderer& operator=(SceneRenderer&&) noexcept;

  std::vector<RenderedView> Render(const TubeScene& scene, const RenderOptions& options,
                                   uint32_t seed) const;
  // One camera's image alone, for the virtual rig, about three times
  // cheaper: the tube, its tapes, shading and shadow are Render()'s (without
  // noise the images agree to one grey level, in a few shadow pixels where
  // the shadow's warp rounds differently); the backdrop away from the tube and its
  // shadow comes from one of a few pre-rendered noisy backdrops (their noise
  // repeats across images; with an exposure_gain other than 1 it is scaled
  // after rounding, so there too it may be one grey level off), and no
  // background or truth mask is made. Supersampling is honoured as in Render().
  // Thread-safe; a pool rebuilds when the backdrop options change.
  cv::Mat RenderImage(size_t camera, const TubeScene& scene, const RenderOptions& options,
                      uint32_t seed) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shapesense
