#pragma once

#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/centerline/voxel_body.h"
#include "libs/geometry/types.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

// A tape band found on the body.
struct MarkerOnCurve {
  double arc_length = 0.0;    // along the centreline, mm
  Vec3 point = Vec3::Zero();  // on the centreline
  int voxels = 0;
};

// Tape bands from the body's marker-labelled voxels: in order of geodesic
// distance, a gap of more than `gap` mm starts a new band. A band of at least
// `min_voxels` voxels is placed where its centroid projects onto the
// centreline (a band is a ring around the axis, so its centroid lies on the
// axis at the band's centre). Base → tip.
std::vector<MarkerOnCurve> FindMarkers(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, const Polyline& centerline,
                                       const std::vector<double>& arc, int min_voxels, double gap);

// Sub-voxel band centres from the images. In each camera the labels are read
// along the projected centreline around the band; the run of tape pixels
// there gives the band's two ends to about a pixel. The pixel on the
// projected axis at arc s shows the tube's front surface, which lies at arc
// s + radius·cot θ (θ between the axis and the direction to the camera), so
// both ends, and the centre, appear shifted by that much; it is added back.
// (The carved marker voxels carry a mixture of these shifts, about a radius.)
// Combined over the cameras that see the whole band unoccluded; a band no
// camera sees keeps its place. Markers stay ordered base → tip.
void RefineMarkersInImages(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                           const Polyline& centerline, const std::vector<double>& arc,
                           double radius, std::vector<MarkerOnCurve>* markers);

}  // namespace shapesense
