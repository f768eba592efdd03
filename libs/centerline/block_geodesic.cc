#include "libs/centerline/block_geodesic.h"

#include <cmath>
#include <limits>

namespace shapesense {
namespace {

using Point = std::array<int, 3>;

Point BlockOf(const Point& voxel) { return {voxel[0] >> 1, voxel[1] >> 1, voxel[2] >> 1}; }

// The blocks that hold a voxel, as a cloud on a grid of twice the spacing
// (a block's centre is the mean of its voxels' centres), and each voxel's
// block.
struct Blocks {
  VoxelCloud cloud;
  std::vector<int32_t> of_voxel;
};

Blocks BlocksOf(const VoxelCloud& cloud, const VoxelGraph& graph) {
  Blocks blocks;
  VoxelGrid& grid = blocks.cloud.grid;
  grid.voxel_size = 2.0 * cloud.grid.voxel_size;
  grid.origin = cloud.grid.origin + Vec3::Constant(0.5 * cloud.grid.voxel_size);
  for (size_t axis = 0; axis < 3; ++axis) grid.dims[axis] = (cloud.grid.dims[axis] + 1) / 2;
  BoxBitmap occupied(BlockOf(graph.low()), BlockOf(graph.high()), 0);
  for (int32_t i = 0; i < static_cast<int32_t>(graph.size()); ++i) {
    occupied.Set(BlockOf(graph.coordinates(i)));
  }
  occupied.FinishRanks();
  // In bitmap order, which is the block grid's linear order: sorted.
  occupied.ForEachSet([&](const Point& b) {
    blocks.cloud.voxels.push_back(static_cast<int32_t>(grid.Index(b[0], b[1], b[2])));
  });
  blocks.cloud.labels.assign(blocks.cloud.voxels.size(), 0);
  blocks.of_voxel.reserve(graph.size());
  for (int32_t i = 0; i < static_cast<int32_t>(graph.size()); ++i) {
    blocks.of_voxel.push_back(occupied.Rank(BlockOf(graph.coordinates(i))));
  }
  return blocks;
}

// Gradient of the distance at block b, per block step: least squares over
// its neighbours in the body, each weighted by 1 / step². A small ridge
// keeps a block whose neighbours lie along one line (a thin body) solvable.
// Neighbours sit at integer offsets, so the sums are kept as scalars.
Vec3 GradientAt(const VoxelGraph& graph, const GeodesicBody& body, int32_t b) {
  const float d = body.distance[static_cast<size_t>(b)];
  const std::array<int, 3>& c = graph.coordinates(b);
  double xx = 1e-3, xy = 0.0, xz = 0.0, yy = 1e-3, yz = 0.0, zz = 1e-3;
  Vec3 right = Vec3::Zero();
  graph.ForEachNeighbor(b, [&](int32_t n, int differing) {
    const float dn = body.distance[static_cast<size_t>(n)];
    if (!std::isfinite(dn)) return;
    const std::array<int, 3>& o = graph.coordinates(n);
    const double x = o[0] - c[0];
    const double y = o[1] - c[1];
    const double z = o[2] - c[2];
    const double w = 1.0 / differing;  // 1 / |step|² in block steps
    xx += w * x * x;
    xy += w * x * y;
    xz += w * x * z;
    yy += w * y * y;
    yz += w * y * z;
    zz += w * z * z;
    right += (w * (dn - d)) * Vec3(x, y, z);
  });
  Mat3 normal;
  normal << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  // Symmetric positive definite and 3×3: the adjugate is cheapest.
  Mat3 adjugate;
  adjugate << yy * zz - yz * yz, xz * yz - xy * zz, xy * yz - xz * yy,  //
      xz * yz - xy * zz, xx * zz - xz * xz, xy * xz - xx * yz,          //
      xy * yz - xz * yy, xy * xz - xx * yz, xx * yy - xy * xy;
  return adjugate * right / (xx * adjugate(0, 0) + xy * adjugate(1, 0) + xz * adjugate(2, 0));
}

// Body voxels in order of distance, a bucket per voxel size (a counting
// sort: no comparisons).
std::vector<int32_t> OrderByDistance(const std::vector<float>& distance, double unit) {
  float largest = 0.0f;
  for (const float d : distance) {
    if (std::isfinite(d)) largest = std::max(largest, d);
  }
  std::vector<int32_t> first(static_cast<size_t>(largest / unit) + 2, 0);
  for (const float d : distance) {
    if (std::isfinite(d)) ++first[static_cast<size_t>(d / unit) + 1];
  }
  for (size_t k = 1; k < first.size(); ++k) first[k] += first[k - 1];
  std::vector<int32_t> order(static_cast<size_t>(first.back()));
  for (int32_t i = 0; i < static_cast<int32_t>(distance.size()); ++i) {
    const float d = distance[static_cast<size_t>(i)];
    if (std::isfinite(d)) order[static_cast<size_t>(first[static_cast<size_t>(d / unit)]++)] = i;
  }
  return order;
}

}  // namespace

GeodesicBody FindGeodesicBodyByBlocks(const VoxelCloud& cloud, const VoxelGraph& graph,
                                      const Vec3& base_point, double max_base_distance,
                                      double seed_margin) {
  const Blocks blocks = BlocksOf(cloud, graph);
  const VoxelGraph block_graph(blocks.cloud);
  // A block's centre lies up to √3 voxels from its voxels' centres.
  const double voxel = cloud.grid.voxel_size;
  const GeodesicBody coarse =
      FindGeodesicBody(blocks.cloud, block_graph, base_point,
                       max_base_distance + std::sqrt(3.0) * voxel, seed_margin + 2.0 * voxel);
  GeodesicBody body;
  body.error = coarse.error;
  if (!body.error.empty()) return body;
  std::vector<Vec3> gradient(blocks.cloud.voxels.size(), Vec3::Zero());
  for (const int32_t b : coarse.members) {
    gradient[static_cast<size_t>(b)] =
        GradientAt(block_graph, coarse, b) / blocks.cloud.grid.voxel_size;
  }
  std::vector<uint8_t> is_seed(blocks.cloud.voxels.size(), 0);
  for (const int32_t b : coarse.seeds) is_seed[static_cast<size_t>(b)] = 1;
  body.distance.assign(cloud.voxels.size(), std::numeric_limits<float>::infinity());
  for (int32_t i = 0; i < static_cast<int32_t>(cloud.voxels.size()); ++i) {
    const size_t b = static_cast<size_t>(blocks.of_voxel[static_cast<size_t>(i)]);
    const float d = coarse.distance[b];
    if (!std::isfinite(d)) continue;
    const Vec3 offset =
        VoxelCenter(cloud.grid, graph.coordinates(i)) -
        VoxelCenter(blocks.cloud.grid, block_graph.coordinates(static_cast<int32_t>(b)));
    body.distance[static_cast<size_t>(i)] =
        std::max(0.0f, d + static_cast<float>(gradient[b].dot(offset)));
    if (is_seed[b]) body.seeds.push_back(i);
  }
  body.members = OrderByDistance(body.distance, voxel);
  return body;
}

}  // namespace shapesense
