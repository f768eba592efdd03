#include "libs/sim/manipulator_scene.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

std::string Expect(bool ok, const std::string& key, const std::string& expected, double got) {
  if (ok) return {};
  std::ostringstream text;
  text << key << ": expected " << expected << ", got " << got;
  return text.str();
}

void CheckInputs(const Configuration& q, const SectionLengths& rest, const Pose3& world_from_base,
                 const ManipulatorSceneOptions& options) {
  std::string error = options.Validate();
  if (error.empty()) error = ManipulatorGeometry{rest, world_from_base, options.tapes}.Validate();
  if (!error.empty()) throw std::invalid_argument("SceneOfConfiguration: " + error);
  if (!q.allFinite() || !(q(kStrainProximal) < 1.0) || !(q(kStrainDistal) < 1.0)) {
    throw std::invalid_argument(
        "SceneOfConfiguration: expected a finite configuration with strains below 1");
  }
}

// The base-frame centreline from `start` along the proximal section on (the
// proximal section is the straight run of points on the y axis before the
// distal section).
Polyline BodyFrom(const Configuration& q, const SectionLengths& rest, double start,
                  double spacing) {
  const Polyline whole = CenterlineFromConfiguration(q, rest, spacing);
  const std::vector<double> arc = CumulativeArcLength(whole);
  Polyline body = {PointAtArcLength(whole, arc, start)};
  for (size_t i = 0; i < whole.size(); ++i) {
    if (arc[i] > start + 1e-9) body.push_back(whole[i]);
  }
  return body;
}

}  // namespace

std::string ManipulatorSceneOptions::Validate() const {
  for (const double channel : tape_bgr) {
    if (!(channel >= 0.0 && channel <= 255.0)) {
      return Expect(false, "tape_bgr", "values in 0-255", channel);
    }
  }
  for (const std::string& error :
       {Expect(radius >= 0.5 && radius <= 20.0, "radius", "0.5-20", radius),
        Expect(body_start >= 0.0 && std::isfinite(body_start), "body_start", "a number >= 0",
               body_start),
        Expect(lead_in_length >= 0.0 && std::isfinite(lead_in_length), "lead_in_length",
               "a number >= 0", lead_in_length),
        Expect(spacing >= 0.01 && spacing <= 0.5, "spacing", "0.01-0.5", spacing),
        tapes.Validate().empty() ? "" : "tapes." + tapes.Validate(),
        Expect(band_width > 0.0 && std::isfinite(band_width), "band_width", "a positive number",
               band_width),
        // Bands that overlap would be seen as one.
        Expect(tapes.proximal_band_before_junction == 0.0 ||
                   tapes.proximal_band_before_junction > 2.0 * band_width,
               "tapes.proximal_band_before_junction",
               "0 or more than two band widths (a gap between the bands)",
               tapes.proximal_band_before_junction),
        Expect(tapes.distal_band_before_tip >= band_width, "tapes.distal_band_before_tip",
               "at least a band width (the band on the tube)", tapes.distal_band_before_tip)}) {
    if (!error.empty()) return error;
  }
  return {};
}

TubeScene SceneOfConfiguration(const Configuration& q, const SectionLengths& rest,
                               const Pose3& world_from_base,
                               const ManipulatorSceneOptions& options) {
  CheckInputs(q, rest, world_from_base, options);
  const double start = std::min(options.body_start, CompressedLengths(q, rest).proximal);
  TubeScene scene;
  for (const Vec3& p : BodyFrom(q, rest, start, options.spacing)) {
    scene.centerline.push_back(world_from_base * p);
  }
  scene.radius = options.radius;
  scene.lead_in_length = options.lead_in_length;
  for (const double s : TapeArcLengths(q, rest, options.tapes)) {
    if (s < start) continue;  // on the part the lead-in stands for
    TapeBand band;
    band.center_arc_length = s - start;
    band.width = options.band_width;
    for (size_t c = 0; c < 3; ++c) {
      band.bgr[c] = static_cast<uint8_t>(std::lround(options.tape_bgr[c]));
    }
    scene.tapes.push_back(band);
  }
  scene.configuration = q;
  return scene;
}

}  // namespace shapesense
