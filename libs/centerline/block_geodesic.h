#pragma once

#include "libs/carving/voxel_grid.h"
#include "libs/centerline/voxel_body.h"
#include "libs/geometry/types.h"

namespace shapesense {

// FindGeodesicBody at a third of the cost. The search runs on blocks of
// 2×2×2 voxels: the same steps, twice as long, over a third to a quarter as
// many nodes. A voxel's distance is then its block's plus its offset from
// the block's centre along the gradient of the distance there (a least
// squares fit over the neighbouring blocks), so distances stay continuous at
// the voxel scale. `members` is in order of distance to within a voxel.
GeodesicBody FindGeodesicBodyByBlocks(const VoxelCloud& cloud, const VoxelGraph& graph,
                                      const Vec3& base_point, double max_base_distance,
                                      double seed_margin);

}  // namespace shapesense
