#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "libs/carving/voxel_grid.h"
#include "libs/centerline/box_bitmap.h"
#include "libs/geometry/types.h"

namespace shapesense {

// The occupied voxels of a cloud as a graph: each voxel is joined to its
// occupied 26-neighbours. Neighbours are found without a search: the cloud
// as a bitmap over its bounding box (padded by a voxel), where a voxel's
// index in the cloud is its rank (see BoxBitmap).
class VoxelGraph {
 public:
  explicit VoxelGraph(const VoxelCloud& cloud);

  size_t size() const { return coordinates_.size(); }
  // Grid coordinates (x, y, z) of voxel i of the cloud.
  const std::array<int, 3>& coordinates(int32_t i) const {
    return coordinates_[static_cast<size_t>(i)];
  }
  // The smallest and largest grid coordinates of the cloud's voxels.
  const std::array<int, 3>& low() const { return low_; }
  const std::array<int, 3>& high() const { return high_; }

  // Calls visit(j, differing) for each occupied neighbour j of voxel i, where
  // `differing` (1-3) counts the coordinates in which they differ.
  template <class Visit>
  void ForEachNeighbor(int32_t i, Visit&& visit) const;

 private:
  std::vector<std::array<int, 3>> coordinates_;
  std::array<int, 3> low_{};
  std::array<int, 3> high_{};
  BoxBitmap occupied_;
};

template <class Visit>
void VoxelGraph::ForEachNeighbor(int32_t i, Visit&& visit) const {
  const int64_t center = occupied_.BitOf(coordinates_[static_cast<size_t>(i)]);
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      const int64_t first = center - 1 + dy * occupied_.stride_y() + dz * occupied_.stride_z();
      const unsigned row = occupied_.ThreeBits(first);
      if (row == 0) continue;
      // The voxels of a row are consecutive in the cloud: one rank serves all three.
      const int32_t rank = occupied_.RankOfBit(first);
      const int rows_differing = (dy != 0) + (dz != 0);
      const bool self_row = dy == 0 && dz == 0;
      if (row & 1u) visit(rank, rows_differing + 1);
      if ((row & 2u) && !self_row) visit(rank + static_cast<int32_t>(row & 1u), rows_differing);
      if (row & 4u) {
        visit(rank + static_cast<int32_t>((row & 1u) + ((row >> 1) & 1u)), rows_differing + 1);
      }
    }
  }
}

// The body: the voxels reached through the graph from the base, with their
// geodesic distance from the base point (the length of the shortest path
// through occupied voxels, steps of 1, √2 and √3 voxels). Unlike an angle
// about a fixed centre, this orders the body for bends of any angle.
struct GeodesicBody {
  std::string error;             // empty on success
  std::vector<float> distance;   // per cloud voxel, mm; +inf outside the body
  std::vector<int32_t> members;  // cloud voxels of the body, by increasing distance
  std::vector<int32_t> seeds;    // cloud voxels the search started from
};

// Starts from the voxels nearest the base point: those within `seed_margin`
// of the nearest one (and within `max_base_distance` of the base point), each
// at its Euclidean distance from the base point. Fails when no voxel lies
// within `max_base_distance`.
GeodesicBody FindGeodesicBody(const VoxelCloud& cloud, const VoxelGraph& graph,
                              const Vec3& base_point, double max_base_distance, double seed_margin);

// Centroid of the body voxels whose geodesic distance falls in one slice.
struct BodySlice {
  Vec3 centroid = Vec3::Zero();
  double distance = 0.0;  // mean geodesic distance of its voxels, mm
  int count = 0;
};

// Slices of equal geodesic distance, `width` mm wide, base → tip; empty slices
// are left out.
std::vector<BodySlice> SliceByDistance(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, double width);

inline Vec3 VoxelCenter(const VoxelGrid& grid, const std::array<int, 3>& c) {
  return grid.Center(c[0], c[1], c[2]);
}

}  // namespace shapesense
