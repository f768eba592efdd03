#pragma once

// The configuration q = [kappa_x, kappa_z, eps0, eps1] from a sensed shape
// (docs/mechanics.md, "Sensing the configuration"): the compressed section
// lengths from the tape markers, then a circular-arc fit (arc_fit.h) of the
// sensed distal section in the base frame.
//
// The tape layout: a band centred at the junction of the two sections, a
// band a fixed rest distance before the tip, and optionally a band on the
// proximal section a fixed rest distance before the junction. Strain is
// uniform along each section, so
//   eps1 = 1 - (s_distal - s_junction) / (L1 - distal_band_before_tip)
//          (or 1 - (s_tip - s_junction) / L1 from the sensed tip),
//   eps0 = 1 - (s_junction - s_proximal) / proximal_band_before_junction
//          (or, without that band, 1 - y_junction / L0, y_junction the
//          junction band's distance from the base along the base axis).
// Only differences of arc lengths are used, so it does not matter where the
// sensed centreline starts (the workspace's face, not the base, for a long
// proximal section).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libs/geometry/types.h"
#include "libs/mechanics/arc_fit.h"
#include "libs/mechanics/configuration.h"

namespace shapesense {

// Where the tape bands sit on the manipulator, as rest distances (mm).
// Bands base → tip: [proximal band,] junction band, distal band.
struct TapeLayout {
  // Rest distance from a band on the proximal section to the junction band,
  // mm; 0: no proximal band (eps0 then from the junction band's distance
  // from the base, which needs an exact world_from_base).
  double proximal_band_before_junction = 0.0;
  // Rest distance of the distal band before the tip, mm.
  double distal_band_before_tip = 10.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("proximal_band_before_junction", proximal_band_before_junction,
          "rest distance of a proximal band before the junction band, mm (0: no such band; "
          "eps0 from the junction's distance from the base)");
    visit("distal_band_before_tip", distal_band_before_tip,
          "rest distance of the distal band before the tip, mm (> 0)");
  }
  std::string Validate() const;

  int BandCount() const { return proximal_band_before_junction > 0.0 ? 3 : 2; }
};

// What the sensing knows of the manipulator: the model's rest lengths, where
// its base is in the cameras' world, and its tapes.
struct ManipulatorGeometry {
  SectionLengths rest;
  Pose3 world_from_base = Pose3::Identity();
  TapeLayout tapes;

  // "" or "key: expected ..., got ..." (rest lengths positive, bands inside
  // their sections).
  std::string Validate() const;
};

// "" when bands `band_width` mm wide (0: not known, nothing to check) lie
// apart on the manipulator at rest, each on its section; else why not,
// naming band_width and the bands.
std::string CheckBandWidth(const ManipulatorGeometry& geometry, double band_width);

// Arc length from the base of each band's centre in configuration q, mm,
// base → tip ([proximal band,] junction band, distal band).
std::vector<double> TapeArcLengths(const Configuration& q, const SectionLengths& rest,
                                   const TapeLayout& tapes);

struct ConfigurationSensingOptions {
  ArcFitOptions arc_fit;
  // Spacing of the sensed distal points handed to the arc fit, mm. The
  // sensed centreline is a smoothing spline with knots every few mm, so
  // closer points add cost (the fit's covariance grows with their number
  // cubed: ~1 ms at 2 mm, ~8 ms at 1 mm for 140 mm), not information.
  double point_spacing = 2.0;
  // Measure the distal section from the junction band to the sensed tip
  // instead of to the distal band.
  bool distal_length_from_tip = false;
  // Standard deviations of a marker's and of the tip's arc length, mm (for
  // the strains' variances).
  double marker_std = 0.15;
  double tip_std = 0.1;
  // Refusals: strains beyond this (markers that do not fit the layout), a
  // junction band farther than this from the base axis (mm; a wrong
  // world_from_base), a distal section shorter than this (mm), an arc fit
  // whose RMS residual exceeds this (mm; the section is no arc).
  double max_strain = 0.2;
  double max_axis_offset = 5.0;
  double min_distal_length = 10.0;
  double max_rms_residual = 1.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("arc_fit", arc_fit, "circular-arc fit of the distal section");
    visit("point_spacing", point_spacing, "spacing of the distal points fitted, mm (0.1-10)");
    visit("distal_length_from_tip", distal_length_from_tip,
          "distal length from the junction band to the sensed tip (else to the distal band)");
    visit("marker_std", marker_std, "standard deviation of a marker's arc length, mm (>= 0)");
    visit("tip_std", tip_std, "standard deviation of the tip's arc length, mm (>= 0)");
    visit("max_strain", max_strain, "largest |strain| believed (0-0.9)");
    visit("max_axis_offset", max_axis_offset,
          "farthest the junction band may lie from the base axis, mm (> 0)");
    visit("min_distal_length", min_distal_length, "shortest distal section fitted, mm (> 0)");
    visit("max_rms_residual", max_rms_residual, "largest RMS residual of the arc fit, mm (> 0)");
  }
  std::string Validate() const;
};

// The sensed shape, world frame.
struct SensedCenterline {
  Polyline centerline;  // base end → tip; its last point is the tip
  // Arc length of each point, mm; empty: measured along the polyline.
  std::vector<double> arc_length;
  std::vector<double> marker_arc_length;  // tape markers, base → tip, same origin
};

// q as measured from one sensed shape (not libs/control's SensedConfiguration,
// the controller's view of the newest sample).
struct ConfigurationMeasurement {
  bool valid = false;
  std::string reason;  // why not, when not valid
  Configuration q = Configuration::Zero();
  // Curvature block from the arc fit, strain block from marker_std/tip_std.
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
  double rms_residual = 0.0;                  // of the arc fit, mm
  double curvature = 0.0;                     // |kappa|, 1/mm
  double bend_direction = 0.0;                // phi, rad (arc_fit.h)
  SectionLengths measured;                    // compressed lengths L0 (1 - eps0), L1 (1 - eps1), mm
  Pose3 world_from_base = Pose3::Identity();  // given, or estimated with the arc
};

// q from a sensed shape; never throws: an invalid result says why (options
// or geometry that fail validation, a tape marker missing or extra, markers
// that do not fit the layout, a section too short, a fit that did not
// converge or does not fit).
ConfigurationMeasurement SenseConfiguration(const SensedCenterline& shape,
                                            const ManipulatorGeometry& geometry,
                                            const ConfigurationSensingOptions& options);

}  // namespace shapesense
