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
  // Edge of the coarsest block of the hierarchical search, voxels (a power of 2).
  int coarse_block = 16;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("voxel_size", voxel_size, "edge of one voxel, mm (> 0)");
    visit("min_marker_views", min_marker_views, "cameras that must see tape at a marker voxel (>= 1)");
    visit("coarse_block", coarse_block, "coarsest block of the hierarchical search, voxels (power of 2, 2-64)");
  }
  std::string Validate() const;
};

// Called with the fraction done (0-1) during the lookup-table build.
using ProgressCallback = std::function<void(double fraction)>;

// Voxel carving over the rig's workspace. A voxel is occupied when the pixel
// its centre projects to (through the lookup table) is inside the silhouette
// in every camera; a voxel whose centre falls outside any image is empty.
//
// Two searches give the same occupancy, voxel for voxel:
//  - CarveFullScan: the reference's baseline, every voxel through the table;
//  - CarveHierarchical: coarse-to-fine; a block is discarded when, in some
//    camera, the pixel bounds of all its voxels' table entries hold no
//    silhouette pixel (summed-area tables), and refined otherwise.
class Carver {
 public:
  // Builds the voxel→pixel lookup table and the block bounds of the hierarchy.
  // Throws std::invalid_argument on a rig or options that fail validation.
  Carver(const Rig& rig, const CarvingOptions& options, const ProgressCallback& progress = {});
  ~Carver();
  Carver(const Carver&) = delete;
  Carver& operator=(const Carver&) = delete;

  // `silhouettes` in the order of rig.cameras. Throws std::invalid_argument
  // on a wrong count or image size.
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
