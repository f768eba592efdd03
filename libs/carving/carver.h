#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

struct CarvingOptions {
  // Edge of one voxel, mm; the grid covers the rig's workspace.
  double voxel_size = 1.0;
  // A voxel is a marker when at least this many cameras see tape at it.
  int min_marker_views = 2;
  // Edge of the coarsest block of the hierarchical search, voxels (a power of
  // 2). At 256³ with a thin tube, 16, 32 and 64 ran within noise of each other
  // and 8 was ~40% slower; 32 tests a third as many blocks as 16. The
  // table is padded to whole coarse blocks, so for a grid that is not a
  // multiple of 32 a smaller block can save memory (200³: 224³ slots at 32,
  // 208³ at 16).
  int coarse_block = 32;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("voxel_size", voxel_size, "edge of one voxel, mm (> 0)");
    visit("min_marker_views", min_marker_views,
          "cameras that must see tape at a marker voxel (>= 1)");
    visit("coarse_block", coarse_block,
          "coarsest block of the hierarchical search, voxels (power of 2, 2-64)");
  }
  std::string Validate() const;
};

// Called with the fraction done (0-1) during the lookup-table build.
using ProgressCallback = std::function<void(double fraction)>;

// Voxel carving over the rig's workspace (VoxelGrid::Covering of
// rig.workspace_min/max at options.voxel_size). A voxel is occupied when the
// pixel its centre projects to is inside the silhouette (mask nonzero) in
// every camera; a voxel whose centre is behind a camera or outside its image
// is empty. The pixel of a voxel is floor(Camera::Project(centre) + 0.5) per
// coordinate, i.e. the pixel whose square holds the projection (the rule of
// Camera::InImage). It is computed once per rig into a lookup table.
//
// A voxel is labelled kLabelMarker when at least min_marker_views cameras
// have kLabelMarker at its pixel, else kLabelBody. A Silhouette with empty
// `labels` sees no marker.
//
// Two searches give the same occupancy and labels, voxel for voxel:
//  - CarveFullScan: the reference's baseline, every voxel through the table;
//  - CarveHierarchical: coarse-to-fine over blocks of coarse_block³ voxels
//    halving down to 4³. Each block stores, per camera, the pixel rectangle
//    bounding its voxels' table pixels (exact by construction) and whether
//    any voxel is outside an image. With summed-area tables of the masks, a
//    block is empty when in some camera its rectangle holds no silhouette
//    pixel, full (all voxels occupied, no further test) when every rectangle
//    is entirely silhouette and no voxel is outside; otherwise it is split,
//    and the voxels of a mixed 4³ block are tested through the table.
//
// Memory: one uint32 per voxel and camera (201 MB at 256³ with 3 cameras)
// plus ~4% for the block bounds; MemoryBytes() reports it. The carve calls
// are const and keep no state between calls, so one Carver may serve
// several threads.
class Carver {
 public:
  // Builds the voxel→pixel lookup table and the block bounds of the hierarchy
  // (about 1 s for 256³ voxels and 3 cameras), calling `progress` as it goes.
  // Throws std::invalid_argument on a rig or options that fail validation,
  // images over 32767 px a side, or a grid over 2^31 voxels.
  Carver(const Rig& rig, const CarvingOptions& options, const ProgressCallback& progress = {});
  ~Carver();
  Carver(const Carver&) = delete;
  Carver& operator=(const Carver&) = delete;

  // `silhouettes` in the order of rig.cameras; masks (and labels, unless
  // empty) CV_8UC1 of the camera's image size. Throws std::invalid_argument
  // on a wrong count, size or type. `out` is overwritten: voxels ascending.
  void CarveFullScan(const std::vector<Silhouette>& silhouettes, VoxelCloud* out) const;
  void CarveHierarchical(const std::vector<Silhouette>& silhouettes, VoxelCloud* out) const;

  const VoxelGrid& grid() const;
  // Bytes held by the lookup table and hierarchy.
  size_t MemoryBytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace shapesense
