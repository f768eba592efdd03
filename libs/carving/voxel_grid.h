#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// A regular grid of cubic voxels. Voxel (x, y, z) has its centre at
// origin + voxel_size * (x, y, z); its linear index is x + dims[0] * (y + dims[1] * z).
struct VoxelGrid {
  Vec3 origin = Vec3::Zero();  // centre of voxel (0, 0, 0), mm
  double voxel_size = 1.0;     // mm
  std::array<int, 3> dims = {0, 0, 0};

  // The grid whose voxels tile the box [min, max] (rounded up to whole voxels).
  static VoxelGrid Covering(const Vec3& min, const Vec3& max, double voxel_size);

  int64_t NumVoxels() const { return int64_t{dims[0]} * dims[1] * dims[2]; }
  int64_t Index(int x, int y, int z) const {
    return x + int64_t{dims[0]} * (y + int64_t{dims[1]} * z);
  }
  std::array<int, 3> Coordinates(int64_t index) const;
  Vec3 Center(int x, int y, int z) const { return origin + voxel_size * Vec3(x, y, z); }
  Vec3 Center(int64_t index) const;
};

// The occupied voxels of a visual hull.
struct VoxelCloud {
  VoxelGrid grid;
  std::vector<int32_t> voxels;  // linear indices, ascending
  std::vector<uint8_t> labels;  // per voxel: kLabelBody or kLabelMarker (libs/silhouette)
};

}  // namespace shapesense
