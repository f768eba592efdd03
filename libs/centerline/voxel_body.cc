#include "libs/centerline/voxel_body.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace shapesense {
namespace {

// Grid coordinates of each voxel, walking the sorted indices row by row so
// that only a new row costs a division.
std::vector<std::array<int, 3>> CoordinatesOf(const VoxelCloud& cloud) {
  std::vector<std::array<int, 3>> out;
  out.reserve(cloud.voxels.size());
  const int64_t width = cloud.grid.dims[0];
  int64_t row_start = -1;
  int y = 0;
  int z = 0;
  for (const int32_t index : cloud.voxels) {
    if (row_start < 0 || index >= row_start + width) {
      const int64_t row = index / width;
      row_start = row * width;
      y = static_cast<int>(row % cloud.grid.dims[1]);
      z = static_cast<int>(row / cloud.grid.dims[1]);
    }
    out.push_back({static_cast<int>(index - row_start), y, z});
  }
  return out;
}

}  // namespace

VoxelGraph::VoxelGraph(const VoxelCloud& cloud) : coordinates_(CoordinatesOf(cloud)) {
  if (!coordinates_.empty()) low_ = high_ = coordinates_.front();
  for (const std::array<int, 3>& c : coordinates_) {
    for (size_t axis = 0; axis < 3; ++axis) {
      low_[axis] = std::min(low_[axis], c[axis]);
      high_[axis] = std::max(high_[axis], c[axis]);
    }
  }
  // One voxel of padding on every side: neighbour lookups never leave the box.
  occupied_ = BoxBitmap(low_, high_, 1);
  for (const std::array<int, 3>& c : coordinates_) occupied_.Set(c);
  occupied_.FinishRanks();
}

namespace {

std::vector<int32_t> SeedsNear(const VoxelCloud& cloud, const VoxelGraph& graph,
                               const Vec3& base_point, double max_base_distance, double seed_margin,
                               std::vector<float>* distance) {
  double nearest = std::numeric_limits<double>::infinity();
  std::vector<double> to_base(cloud.voxels.size());
  for (size_t i = 0; i < cloud.voxels.size(); ++i) {
    to_base[i] =
        (VoxelCenter(cloud.grid, graph.coordinates(static_cast<int32_t>(i))) - base_point).norm();
    nearest = std::min(nearest, to_base[i]);
  }
  std::vector<int32_t> seeds;
  if (!(nearest <= max_base_distance)) return seeds;
  const double limit = std::min(max_base_distance, nearest + seed_margin);
  for (size_t i = 0; i < to_base.size(); ++i) {
    if (to_base[i] > limit) continue;
    seeds.push_back(static_cast<int32_t>(i));
    (*distance)[i] = static_cast<float>(to_base[i]);
  }
  return seeds;
}

// Step lengths to a neighbour that differs in 1, 2 or 3 coordinates.
std::array<float, 4> StepLengths(double voxel_size) {
  return {0.0f, static_cast<float>(voxel_size), static_cast<float>(voxel_size * std::sqrt(2.0)),
          static_cast<float>(voxel_size * std::sqrt(3.0))};
}

// Lowers the distance of each neighbour of voxel i that a step from i
// shortens, and reports it.
template <class OnImproved>
void RelaxNeighbors(const VoxelGraph& graph, int32_t i, const std::array<float, 4>& step,
                    std::vector<float>* distance, OnImproved&& on_improved) {
  const float d = (*distance)[static_cast<size_t>(i)];
  graph.ForEachNeighbor(i, [&](int32_t j, int differing) {
    const float candidate = d + step[static_cast<size_t>(differing)];
    if (candidate < (*distance)[static_cast<size_t>(j)]) {
      (*distance)[static_cast<size_t>(j)] = candidate;
      on_improved(j, candidate);
    }
  });
}

}  // namespace

GeodesicBody FindGeodesicBody(const VoxelCloud& cloud, const VoxelGraph& graph,
                              const Vec3& base_point, double max_base_distance,
                              double seed_margin) {
  GeodesicBody body;
  const float infinity = std::numeric_limits<float>::infinity();
  body.distance.assign(cloud.voxels.size(), infinity);
  body.seeds = SeedsNear(cloud, graph, base_point, max_base_distance, seed_margin, &body.distance);
  if (body.seeds.empty()) {
    body.error = "no occupied voxel within max_base_distance (" +
                 std::to_string(max_base_distance) + " mm) of the base point";
    return body;
  }
  // Dijkstra with a bucket queue (Dial's algorithm): bucket k holds the
  // voxels at distance [k, k + 1) voxels. Every step is at least one voxel,
  // so a voxel's distance is final when its bucket comes up, and pending
  // voxels lie fewer than `ring` buckets ahead (steps ≤ √3; seeds within the
  // margin).
  const double unit = cloud.grid.voxel_size;
  const auto bucket_of = [unit](float d) { return static_cast<int64_t>(d / unit); };
  const int ring = 3 + static_cast<int>(std::ceil(seed_margin / unit));
  std::vector<std::vector<int32_t>> buckets(static_cast<size_t>(ring));
  int64_t current = std::numeric_limits<int64_t>::max();
  for (const int32_t s : body.seeds) {
    const int64_t b = bucket_of(body.distance[static_cast<size_t>(s)]);
    current = std::min(current, b);
    buckets[static_cast<size_t>(b % ring)].push_back(s);
  }
  const std::array<float, 4> step = StepLengths(unit);
  std::vector<uint8_t> settled(cloud.voxels.size(), 0);
  body.members.reserve(cloud.voxels.size());
  std::vector<int32_t> ready;
  for (int empty_run = 0; empty_run < ring; ++current) {
    std::vector<int32_t>& bucket = buckets[static_cast<size_t>(current % ring)];
    empty_run = bucket.empty() ? empty_run + 1 : 0;
    ready.clear();
    for (const int32_t i : bucket) {
      // Skips entries left behind when a voxel moved to an earlier bucket.
      if (!settled[static_cast<size_t>(i)] &&
          bucket_of(body.distance[static_cast<size_t>(i)]) == current) {
        settled[static_cast<size_t>(i)] = 1;
        ready.push_back(i);
      }
    }
    bucket.clear();
    std::sort(ready.begin(), ready.end(), [&body](int32_t a, int32_t b) {
      return body.distance[static_cast<size_t>(a)] < body.distance[static_cast<size_t>(b)];
    });
    for (const int32_t i : ready) {
      body.members.push_back(i);
      RelaxNeighbors(graph, i, step, &body.distance, [&](int32_t j, float d) {
        buckets[static_cast<size_t>(bucket_of(d) % ring)].push_back(j);
      });
    }
  }
  return body;
}

std::vector<BodySlice> SliceByDistance(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, double width) {
  std::vector<BodySlice> slices;
  if (body.members.empty()) return slices;
  // `members` may be ordered only to within a voxel: take the true extremes.
  double start = std::numeric_limits<double>::infinity();
  double end = -start;
  for (const int32_t i : body.members) {
    start = std::min<double>(start, body.distance[static_cast<size_t>(i)]);
    end = std::max<double>(end, body.distance[static_cast<size_t>(i)]);
  }
  slices.resize(static_cast<size_t>((end - start) / width) + 1);
  for (const int32_t i : body.members) {
    const double d = body.distance[static_cast<size_t>(i)];
    BodySlice& slice =
        slices[std::min(slices.size() - 1, static_cast<size_t>((d - start) / width))];
    slice.centroid += VoxelCenter(cloud.grid, graph.coordinates(i));
    slice.distance += d;
    ++slice.count;
  }
  std::erase_if(slices, [](const BodySlice& s) { return s.count == 0; });
  for (BodySlice& slice : slices) {
    slice.centroid /= slice.count;
    slice.distance /= slice.count;
  }
  return slices;
}

}  // namespace shapesense
