#include "libs/carving/voxel_grid.h"

#include <cmath>
#include <stdexcept>

namespace shapesense {

VoxelGrid VoxelGrid::Covering(const Vec3& min, const Vec3& max, double voxel_size) {
  if (!(voxel_size > 0.0) || !std::isfinite(voxel_size)) {
    throw std::invalid_argument("VoxelGrid::Covering: voxel_size must be positive and finite");
  }
  if (!(min.array() < max.array()).all() || !min.allFinite() || !max.allFinite()) {
    throw std::invalid_argument("VoxelGrid::Covering: min must be below max on every axis");
  }
  VoxelGrid grid;
  grid.voxel_size = voxel_size;
  grid.origin = min + Vec3::Constant(0.5 * voxel_size);
  for (int axis = 0; axis < 3; ++axis) {
    // The tolerance keeps an extent that is a whole number of voxels (256 mm
    // of 1 mm voxels) from gaining a voxel through rounding error.
    const double voxels = (max[axis] - min[axis]) / voxel_size;
    if (voxels > 1e9) throw std::invalid_argument("VoxelGrid::Covering: too many voxels");
    grid.dims[axis] = std::max(1, static_cast<int>(std::ceil(voxels - 1e-9)));
  }
  return grid;
}

std::array<int, 3> VoxelGrid::Coordinates(int64_t index) const {
  const int64_t x = index % dims[0];
  const int64_t yz = index / dims[0];
  return {static_cast<int>(x), static_cast<int>(yz % dims[1]), static_cast<int>(yz / dims[1])};
}

Vec3 VoxelGrid::Center(int64_t index) const {
  const auto [x, y, z] = Coordinates(index);
  return Center(x, y, z);
}

}  // namespace shapesense
