#include "libs/sim/tube_scene.h"

#include <cmath>
#include <sstream>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

std::string Describe(const std::string& key, const std::string& expected, double got) {
  std::ostringstream text;
  text << key << ": expected " << expected << ", got " << got;
  return text.str();
}

std::string CheckColour(const std::string& key, const std::array<double, 3>& bgr) {
  for (const double channel : bgr) {
    if (!(channel >= 0.0 && channel <= 255.0)) return Describe(key, "values in 0-255", channel);
  }
  return {};
}

// The shading model's name and its parameters.
std::string CheckShading(const RenderOptions& options) {
  if (options.shading != "lambert" && options.shading != "wrap" && options.shading != "phong") {
    return "shading: expected lambert, wrap or phong, got " + options.shading;
  }
  if (!(options.wrap >= 0.0 && options.wrap <= 1.0))
    return Describe("wrap", "a number in [0, 1]", options.wrap);
  if (!(options.specular >= 0.0 && options.specular <= 1.0))
    return Describe("specular", "a number in [0, 1]", options.specular);
  if (!(options.shininess >= 1.0 && options.shininess <= 1000.0))
    return Describe("shininess", "a number in [1, 1000]", options.shininess);
  return {};
}

// What the camera does with the light: exposure and rays per pixel.
std::string CheckExposure(const RenderOptions& options) {
  if (!(options.exposure_gain >= 0.5 && options.exposure_gain <= 2.0))
    return Describe("exposure_gain", "a number in [0.5, 2]", options.exposure_gain);
  if (options.supersampling < 1 || options.supersampling > 4)
    return Describe("supersampling", "an integer in 1-4", options.supersampling);
  return {};
}

}  // namespace

GroundTruth TruthOf(const TubeScene& scene) {
  GroundTruth truth;
  truth.centerline = scene.centerline;
  truth.configuration = scene.configuration;
  if (scene.centerline.empty()) return truth;
  truth.tip = scene.centerline.back();
  const std::vector<double> arc = CumulativeArcLength(scene.centerline);
  truth.length = arc.back();
  for (const TapeBand& tape : scene.tapes) {
    truth.markers.push_back(PointAtArcLength(scene.centerline, arc, tape.center_arc_length));
    truth.marker_arc_length.push_back(tape.center_arc_length);
  }
  return truth;
}

std::string RenderOptions::Validate() const {
  if (std::string error = CheckColour("backdrop_bgr", backdrop_bgr); !error.empty()) return error;
  if (std::string error = CheckColour("body_bgr", body_bgr); !error.empty()) return error;
  if (!(backdrop_vignette >= 0.0 && backdrop_vignette < 1.0)) {
    return Describe("backdrop_vignette", "a number in [0, 1)", backdrop_vignette);
  }
  const double light_norm = std::hypot(light_direction[0], light_direction[1], light_direction[2]);
  if (!(light_norm > 1e-9 && std::isfinite(light_norm))) {
    return "light_direction: expected a finite non-zero vector, got one of length " +
           std::to_string(light_norm);
  }
  if (!(ambient >= 0.0 && ambient <= 2.0))
    return Describe("ambient", "a number in [0, 2]", ambient);
  if (!(diffuse >= 0.0 && diffuse <= 2.0))
    return Describe("diffuse", "a number in [0, 2]", diffuse);
  if (std::string error = CheckShading(*this); !error.empty()) return error;
  if (std::string error = CheckExposure(*this); !error.empty()) return error;
  if (!(noise_sigma >= 0.0 && noise_sigma <= 50.0)) {
    return Describe("noise_sigma", "a number in [0, 50]", noise_sigma);
  }
  if (!(shadow_strength >= 0.0 && shadow_strength < 1.0)) {
    return Describe("shadow_strength", "a number in [0, 1)", shadow_strength);
  }
  for (const double offset : shadow_offset_px) {
    if (!(std::abs(offset) <= 200.0))
      return Describe("shadow_offset_px", "values in [-200, 200]", offset);
  }
  if (!(shadow_blur_px >= 0.0 && shadow_blur_px <= 50.0)) {
    return Describe("shadow_blur_px", "a number in [0, 50]", shadow_blur_px);
  }
  return {};
}

ShadingModel RenderOptions::shading_model() const {
  if (shading == "wrap") return ShadingModel::kWrap;
  if (shading == "phong") return ShadingModel::kPhong;
  return ShadingModel::kLambert;
}

}  // namespace shapesense
