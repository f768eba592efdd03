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
  double arc_length = 0.0;    // of the band's centre along the centreline, mm
  Vec3 point = Vec3::Zero();  // on the centreline
  int voxels = 0;             // marker voxels of the cluster that seeded it
  // The band's confidence: the standard error of its centre along the tube,
  // mm, from the spread of its edges in each view and the views' agreement
  // (the voxel size when it was placed from voxels alone).
  double std_mm = 0.0;
  double width = 0.0;  // measured along the tube, mm (0 when placed from voxels)
  int views = 0;       // cameras whose edges placed it
};

// Tape bands from the body's marker-labelled voxels: in order of geodesic
// distance, a gap of more than `gap` mm starts a new band. A band of at least
// `min_voxels` voxels is placed where its centroid projects onto the
// centreline (a band is a ring around the axis, so its centroid lies on the
// axis at the band's centre). Base → tip.
std::vector<MarkerOnCurve> FindMarkers(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, const Polyline& centerline,
                                       const std::vector<double>& arc, int min_voxels, double gap);

// What is known of the bands before they are looked for in the images.
struct BandPrior {
  // The bands' width along the tube, mm (0: not known; bands of 1-12 mm are
  // then accepted). A view whose band is far from this width saw something
  // else (two bands merged, or another part of the tube across it).
  double width = 0.0;
  // How far a seed (a voxel cluster's centre) may lie from its band's
  // centre, mm, besides the views' front-surface shifts: the carved marker
  // voxels lie where the cameras see tape, on the surface facing them, up to
  // radius·cot θ along the axis from the band (θ between the axis and the
  // view; the window grows by the largest).
  double seed_error = 2.0;
};

// Band centres from the tape's edges in the images, to a fraction of a pixel
// (docs/tape.md).
//
// In each camera the tube's visible surface is read along five of its lines
// (generators), at ±45° about the one facing the camera: points at arc s on
// the surface, c(s) + r·(cos φ·u + sin φ·v), u towards the camera. A band's
// edge is a circle in the plane normal to the axis, so each line crosses it
// exactly at the edge's arc length: no correction for the radius, and it
// holds on bends. Along a line the labels are read bilinearly (tape 1, body
// 0) outwards from the seed; each end of the run of tape is refined by
// bisection to where the share crosses one half. Lines of different pixel
// phases averaged make the centre sub-pixel.
//
// Reads where another part of the tube lies between the camera and the
// surface are unreadable. A line counts when its run ends on readable body
// at both sides and has a plausible width; a view, when enough of its lines
// agree; its centre's standard error comes from their spread and the labels'
// quantisation in mm along the tube (a foreshortened view, nearly along the
// axis, spans many mm per pixel and weighs little). The views are fused by
// their inverse variances; with three or more, one that disagrees with the
// others is dropped; two that disagree leave the band ambiguous. A band no
// view places, or an ambiguous one, is removed: it is reported missing,
// never placed from the voxels alone. Markers stay ordered base → tip.
void LocateBandsInImages(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                         const Polyline& centerline, const std::vector<double>& arc, double radius,
                         const BandPrior& prior, std::vector<MarkerOnCurve>* markers);

}  // namespace shapesense
