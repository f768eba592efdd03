#include "libs/mechanics/configuration_sensing.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "libs/core/error.h"
#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

std::string Expect(bool ok, const std::string& key, const std::string& expected, double got) {
  return ok ? "" : key + ": expected " + expected + ", got " + Number(got);
}

bool IsRigid(const Pose3& pose) {
  const Mat3 rotation = pose.linear();
  return pose.matrix().allFinite() &&
         (rotation.transpose() * rotation - Mat3::Identity()).norm() < 1e-6 &&
         rotation.determinant() > 0.0;
}

// The markers' arc lengths, by band, along the sensed centreline.
struct BandArcs {
  double proximal = 0.0;  // only with a proximal band
  double junction = 0.0;
  double distal = 0.0;
};

// What the markers and the base pose tell of the two sections.
struct SectionMeasurement {
  double junction_arc = 0.0;                      // along the sensed centreline, mm
  double junction_height = 0.0;                   // junction band along the base axis, mm
  Configuration strains = Configuration::Zero();  // eps0, eps1 in their slots
  SectionLengths lengths;                         // compressed, mm
  double proximal_strain_std = 0.0;
  double distal_length_std = 0.0;  // mm
};

std::string CheckShape(const SensedCenterline& shape, const std::vector<double>& arc) {
  if (shape.centerline.size() < 2) return "no sensed centreline";
  if (arc.size() != shape.centerline.size()) {
    return "expected an arc length per centreline point, got " + std::to_string(arc.size()) +
           " for " + std::to_string(shape.centerline.size());
  }
  const auto finite = [](double v) { return std::isfinite(v); };
  if (!std::all_of(arc.begin(), arc.end(), finite) ||
      !std::all_of(shape.marker_arc_length.begin(), shape.marker_arc_length.end(), finite)) {
    return "expected finite arc lengths";
  }
  if (!std::is_sorted(arc.begin(), arc.end())) return "expected increasing arc lengths";
  const std::vector<double>& markers = shape.marker_arc_length;
  if (!std::is_sorted(markers.begin(), markers.end())) {
    return "expected the tape markers ordered base to tip";
  }
  if (!markers.empty() && (markers.front() < arc.front() || markers.back() > arc.back())) {
    return "expected the tape markers on the centreline";
  }
  return "";
}

std::string CheckMarkerCount(size_t seen, int expected) {
  if (seen == static_cast<size_t>(expected)) return "";
  return "saw " + std::to_string(seen) + " tape markers, the layout has " +
         std::to_string(expected) +
         (seen < static_cast<size_t>(expected) ? " (a band hidden or not found)"
                                               : " (a stray marker)");
}

BandArcs AssignBands(const std::vector<double>& markers, const TapeLayout& tapes) {
  BandArcs bands;
  const size_t first = tapes.BandCount() == 3 ? 1 : 0;
  if (first == 1) bands.proximal = markers[0];
  bands.junction = markers[first];
  bands.distal = markers[first + 1];
  return bands;
}

std::string CheckStrain(const char* name, double strain, double max_strain) {
  if (std::abs(strain) <= max_strain) return "";
  return std::string("tape markers do not fit the layout: ") + name + " would be " +
         Number(strain) + " (largest believed " + Number(max_strain) + ")";
}

// eps1 and its length's standard deviation, from the distal band or the tip.
void MeasureDistal(const BandArcs& bands, double tip_arc, const ManipulatorGeometry& geometry,
                   const ConfigurationSensingOptions& options, SectionMeasurement* m) {
  const double rest = geometry.rest.distal;
  const double banded_rest = rest - geometry.tapes.distal_band_before_tip;
  if (options.distal_length_from_tip) {
    m->lengths.distal = tip_arc - bands.junction;
    m->distal_length_std = std::hypot(options.marker_std, options.tip_std);
  } else {
    m->lengths.distal = (bands.distal - bands.junction) * rest / banded_rest;
    m->distal_length_std = std::sqrt(2.0) * options.marker_std * rest / banded_rest;
  }
  m->strains(kStrainDistal) = 1.0 - m->lengths.distal / rest;
}

// eps0 from the proximal band, or from the junction band's height on the base axis.
void MeasureProximal(const BandArcs& bands, const ManipulatorGeometry& geometry,
                     const ConfigurationSensingOptions& options, SectionMeasurement* m) {
  const double rest = geometry.rest.proximal;
  const double band_rest = geometry.tapes.proximal_band_before_junction;
  if (band_rest > 0.0) {
    m->lengths.proximal = rest * (bands.junction - bands.proximal) / band_rest;
    m->proximal_strain_std = std::sqrt(2.0) * options.marker_std / band_rest;
  } else {
    m->lengths.proximal = m->junction_height;
    m->proximal_strain_std = options.marker_std / rest;
  }
  m->strains(kStrainProximal) = 1.0 - m->lengths.proximal / rest;
}

// Where the junction band lies relative to the base axis: "" or why it cannot be the start
// of the distal section.
std::string LocateJunction(const SensedCenterline& shape, const std::vector<double>& arc,
                           const ManipulatorGeometry& geometry,
                           const ConfigurationSensingOptions& options, SectionMeasurement* m) {
  const Vec3 in_base =
      geometry.world_from_base.inverse() * PointAtArcLength(shape.centerline, arc, m->junction_arc);
  const double offset = std::hypot(in_base.x(), in_base.z());
  m->junction_height = in_base.y();
  if (offset > options.max_axis_offset) {
    return "the junction band lies " + Number(offset) + " mm off the base axis (at most " +
           Number(options.max_axis_offset) + "): is world_from_base right?";
  }
  if (!(in_base.y() > 0.0))
    return "the junction band lies behind the base: is world_from_base right?";
  return "";
}

std::string MeasureSections(const SensedCenterline& shape, const std::vector<double>& arc,
                            const ManipulatorGeometry& geometry,
                            const ConfigurationSensingOptions& options, SectionMeasurement* m) {
  const std::vector<double>& markers = shape.marker_arc_length;
  if (std::string error = CheckMarkerCount(markers.size(), geometry.tapes.BandCount());
      !error.empty()) {
    return error;
  }
  const BandArcs bands = AssignBands(markers, geometry.tapes);
  m->junction_arc = bands.junction;
  if (std::string error = LocateJunction(shape, arc, geometry, options, m); !error.empty()) {
    return error;
  }
  MeasureDistal(bands, arc.back(), geometry, options, m);
  MeasureProximal(bands, geometry, options, m);
  for (const auto& [name, index] : {std::pair{"eps0", kStrainProximal}, {"eps1", kStrainDistal}}) {
    if (std::string error = CheckStrain(name, m->strains(index), options.max_strain);
        !error.empty()) {
      return error;
    }
  }
  // Both the measured section and the sensed one the arc is fitted to.
  const double shortest = std::min(m->lengths.distal, arc.back() - bands.junction);
  if (shortest < options.min_distal_length) {
    return "distal section too short: " + Number(shortest) + " mm (at least " +
           Number(options.min_distal_length) + ")";
  }
  return "";
}

// The sensed centreline from the junction band to the tip, evenly resampled.
Polyline DistalPoints(const SensedCenterline& shape, const std::vector<double>& arc,
                      double junction_arc, double spacing) {
  const double length = arc.back() - junction_arc;
  const int steps = std::max(2, static_cast<int>(std::ceil(length / spacing - 1e-9)));
  Polyline points;
  for (int k = 0; k <= steps; ++k) {
    points.push_back(PointAtArcLength(shape.centerline, arc, junction_arc + length * k / steps));
  }
  return points;
}

ArcFitInput FitInput(const SensedCenterline& shape, const std::vector<double>& arc,
                     const ManipulatorGeometry& geometry, const SectionMeasurement& m,
                     double spacing) {
  ArcFitInput input;
  input.points = DistalPoints(shape, arc, m.junction_arc, spacing);
  input.distal_length = m.lengths.distal;
  input.distal_length_std = m.distal_length_std;
  // The arc starts where the junction band is: its height on the base axis.
  input.proximal_length = m.junction_height;
  input.rest = geometry.rest;
  input.world_from_base = geometry.world_from_base;
  return input;
}

std::string CheckFit(const ArcFit& fit, const ConfigurationSensingOptions& options) {
  if (!fit.converged) return "arc fit did not converge: " + fit.message;
  if (!(fit.rms_residual <= options.max_rms_residual)) {
    return "the distal section is no arc: fit RMS residual " + Number(fit.rms_residual) +
           " mm (at most " + Number(options.max_rms_residual) + ")";
  }
  return "";
}

void FillResult(const ArcFit& fit, const SectionMeasurement& m, ConfigurationMeasurement* result) {
  result->q = fit.configuration;
  result->q(kStrainProximal) = m.strains(kStrainProximal);
  result->covariance = fit.covariance;
  result->covariance(kStrainProximal, kStrainProximal) = std::pow(m.proximal_strain_std, 2);
  result->rms_residual = fit.rms_residual;
  result->curvature = fit.curvature;
  result->bend_direction = fit.bend_direction;
  result->measured = m.lengths;
  result->world_from_base = fit.world_from_base;
}

}  // namespace

std::string TapeLayout::Validate() const {
  if (std::string e = Expect(
          proximal_band_before_junction >= 0.0 && std::isfinite(proximal_band_before_junction),
          "proximal_band_before_junction", "a number >= 0", proximal_band_before_junction);
      !e.empty()) {
    return e;
  }
  return Expect(distal_band_before_tip > 0.0 && std::isfinite(distal_band_before_tip),
                "distal_band_before_tip", "a positive number", distal_band_before_tip);
}

// Runs once per sensed shape (SenseConfiguration checks its inputs): the
// messages are built only when something is wrong.
std::string ManipulatorGeometry::Validate() const {
  if (!(rest.proximal > 0.0 && std::isfinite(rest.proximal))) {
    return Expect(false, "proximal_length", "a positive number", rest.proximal);
  }
  if (!(rest.distal > 0.0 && std::isfinite(rest.distal))) {
    return Expect(false, "distal_length", "a positive number", rest.distal);
  }
  if (const std::string error = tapes.Validate(); !error.empty()) return "tapes." + error;
  if (!(tapes.distal_band_before_tip < rest.distal)) {
    return Expect(false, "tapes.distal_band_before_tip",
                  "less than the distal length " + Number(rest.distal),
                  tapes.distal_band_before_tip);
  }
  if (!(tapes.proximal_band_before_junction < rest.proximal)) {
    return Expect(false, "tapes.proximal_band_before_junction",
                  "less than the proximal length " + Number(rest.proximal),
                  tapes.proximal_band_before_junction);
  }
  if (!IsRigid(world_from_base)) return "world_from_base: expected a rigid transform";
  return "";
}

std::string CheckBandWidth(const ManipulatorGeometry& geometry, double band_width) {
  if (band_width <= 0.0) return "";
  const TapeLayout& tapes = geometry.tapes;
  const std::string width = "band_width " + Number(band_width) + " mm";
  const double junction_to_distal = geometry.rest.distal - tapes.distal_band_before_tip;
  if (!(junction_to_distal > band_width)) {
    return width + " is wider than the " + Number(junction_to_distal) +
           " mm between the junction and distal bands: bands wider than the spacing between them";
  }
  if (tapes.BandCount() == 3 && !(tapes.proximal_band_before_junction > band_width)) {
    return width + " is wider than the " + Number(tapes.proximal_band_before_junction) +
           " mm between the proximal and junction bands: bands wider than the spacing between "
           "them";
  }
  if (!(tapes.distal_band_before_tip >= 0.5 * band_width)) {
    return width + ": the distal band, centred " + Number(tapes.distal_band_before_tip) +
           " mm before the tip, runs off the tube's end";
  }
  if (!(tapes.proximal_band_before_junction + 0.5 * band_width <= geometry.rest.proximal)) {
    return width + ": the proximal band, centred " + Number(tapes.proximal_band_before_junction) +
           " mm before the junction, runs off the " + Number(geometry.rest.proximal) +
           " mm proximal section";
  }
  return "";
}

std::vector<double> TapeArcLengths(const Configuration& q, const SectionLengths& rest,
                                   const TapeLayout& tapes) {
  const SectionLengths compressed = CompressedLengths(q, rest);
  std::vector<double> arcs;
  if (tapes.BandCount() == 3) {
    arcs.push_back(compressed.proximal -
                   tapes.proximal_band_before_junction * (1.0 - q(kStrainProximal)));
  }
  arcs.push_back(compressed.proximal);
  arcs.push_back(compressed.proximal +
                 (rest.distal - tapes.distal_band_before_tip) * (1.0 - q(kStrainDistal)));
  return arcs;
}

std::string ConfigurationSensingOptions::Validate() const {
  if (const std::string e = arc_fit.Validate(); !e.empty()) return "arc_fit." + e;
  for (const std::string& error :
       {Expect(point_spacing >= 0.1 && point_spacing <= 10.0, "point_spacing", "0.1-10",
               point_spacing),
        Expect(marker_std >= 0.0 && std::isfinite(marker_std), "marker_std", "a number >= 0",
               marker_std),
        Expect(tip_std >= 0.0 && std::isfinite(tip_std), "tip_std", "a number >= 0", tip_std),
        Expect(max_strain > 0.0 && max_strain <= 0.9, "max_strain", "a number in (0, 0.9]",
               max_strain),
        Expect(max_axis_offset > 0.0, "max_axis_offset", "a positive number", max_axis_offset),
        Expect(min_distal_length > 0.0, "min_distal_length", "a positive number",
               min_distal_length),
        Expect(max_rms_residual > 0.0, "max_rms_residual", "a positive number",
               max_rms_residual)}) {
    if (!error.empty()) return error;
  }
  return "";
}

ConfigurationMeasurement SenseConfiguration(const SensedCenterline& shape,
                                            const ManipulatorGeometry& geometry,
                                            const ConfigurationSensingOptions& options) {
  ConfigurationMeasurement result;
  result.world_from_base = geometry.world_from_base;
  const std::vector<double> arc =
      shape.arc_length.empty() ? CumulativeArcLength(shape.centerline) : shape.arc_length;
  SectionMeasurement m;
  for (const std::string& error : {geometry.Validate(), options.Validate()}) {
    result.reason = error;
    if (!result.reason.empty()) return result;
  }
  result.reason = CheckShape(shape, arc);
  if (result.reason.empty()) result.reason = MeasureSections(shape, arc, geometry, options, &m);
  if (!result.reason.empty()) return result;
  const ArcFit fit =
      FitCircularArc(FitInput(shape, arc, geometry, m, options.point_spacing), options.arc_fit);
  result.reason = CheckFit(fit, options);
  if (!result.reason.empty()) return result;
  FillResult(fit, m, &result);
  result.valid = true;
  return result;
}

}  // namespace shapesense
