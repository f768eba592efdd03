#pragma once

// From a configuration to the manipulator's centreline in its base frame:
// the proximal section is straight along +y, compressed to L0 (1 - eps0);
// the distal section continues from there as a constant-curvature arc of
// length L1 (1 - eps1) with curvature vector (kappa_x, 0, kappa_z)
// (arc_geometry.h). Used by the virtual rig's plant and to compare the model
// with sensed shapes.

#include "libs/geometry/types.h"
#include "libs/mechanics/configuration.h"

namespace shapesense {

// Compressed lengths L0 (1 - eps0) and L1 (1 - eps1), mm.
SectionLengths CompressedLengths(const Configuration& q, const SectionLengths& rest);

// Pose of the frame at the start of the distal section (its y axis along the
// centreline), in the base frame.
Pose3 BaseFromDistalStart(const Configuration& q, const SectionLengths& rest);

// Frame at arc length s along the distal section (clamped to it): origin on
// the centreline, y axis along the tangent, x and z turned with the section.
Pose3 BaseFromDistalPoint(const Configuration& q, const SectionLengths& rest, double s);

// The tip's frame in the base frame.
Pose3 BaseFromTip(const Configuration& q, const SectionLengths& rest);

// Centreline from the base to the tip, points at most `spacing` mm apart;
// the start of the distal section and the tip are always points of it.
Polyline CenterlineFromConfiguration(const Configuration& q, const SectionLengths& rest,
                                     double spacing);

// The distal section alone, from its start to the tip, base frame.
Polyline DistalCenterline(const Configuration& q, const SectionLengths& rest, double spacing);

}  // namespace shapesense
