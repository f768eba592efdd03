#include "runtime/lcm/voxel_cloud_message.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "libs/core/error.h"
#include "libs/silhouette/silhouette.h"
#include "runtime/lcm/stage_times.h"

namespace shapesense {
namespace {

std::string ValidateVoxelGrid(const voxel_cloud_t& message) {
  int64_t total = 1;
  for (int axis = 0; axis < 3; ++axis) {
    if (message.dims[axis] < 1) {
      return Expected("dims[" + std::to_string(axis) + "]", ">= 1",
                      std::to_string(message.dims[axis]));
    }
    total *= message.dims[axis];
    if (total > INT32_MAX) return Expected("dims", "at most 2^31 - 1 voxels in all", "more");
  }
  if (!std::isfinite(message.voxel_size) || message.voxel_size <= 0) {
    return Expected("voxel_size", "a positive number", std::to_string(message.voxel_size));
  }
  if (!std::isfinite(message.grid_origin[0]) || !std::isfinite(message.grid_origin[1]) ||
      !std::isfinite(message.grid_origin[2])) {
    return Expected("grid_origin", "finite coordinates", "a non-finite one");
  }
  return {};
}

// Indices in [0, total), each once, in any order.
std::string ValidateVoxelIndices(const std::vector<int32_t>& voxels, int64_t total) {
  std::vector<int32_t> sorted;
  const bool ascending = std::is_sorted(voxels.begin(), voxels.end());
  if (!ascending) {
    sorted = voxels;
    std::sort(sorted.begin(), sorted.end());
  }
  const std::vector<int32_t>& check = ascending ? voxels : sorted;
  if (!check.empty() && (check.front() < 0 || check.back() >= total)) {
    return Expected("voxels", "indices in [0, " + std::to_string(total) + ")",
                    std::to_string(check.front() < 0 ? check.front() : check.back()));
  }
  if (std::adjacent_find(check.begin(), check.end()) != check.end()) {
    return Expected("voxels", "each index once", "a repeated index");
  }
  return {};
}

}  // namespace

voxel_cloud_t VoxelCloudToMessage(const VoxelCloud& cloud) {
  voxel_cloud_t message{};
  for (int axis = 0; axis < 3; ++axis) {
    message.grid_origin[axis] = cloud.grid.origin[axis];
    message.dims[axis] = cloud.grid.dims[static_cast<size_t>(axis)];
  }
  message.voxel_size = cloud.grid.voxel_size;
  message.num_voxels = static_cast<int32_t>(cloud.voxels.size());
  message.voxels = cloud.voxels;
  message.labels.resize(cloud.voxels.size(), 0);
  for (size_t i = 0; i < cloud.labels.size() && i < cloud.voxels.size(); ++i) {
    message.labels[i] = cloud.labels[i] == kLabelMarker ? 1 : 0;
  }
  return message;
}

std::string ValidateVoxelCloudMessage(const voxel_cloud_t& message) {
  if (std::string error = ValidateVoxelGrid(message); !error.empty()) return error;
  if (message.num_voxels < 0 || static_cast<size_t>(message.num_voxels) != message.voxels.size() ||
      message.labels.size() != message.voxels.size()) {
    return Expected("num_voxels",
                    std::to_string(message.voxels.size()) + " voxels and as many labels",
                    std::to_string(message.num_voxels) + " and " +
                        std::to_string(message.labels.size()) + " labels");
  }
  const int64_t total = int64_t{message.dims[0]} * message.dims[1] * message.dims[2];
  if (std::string error = ValidateVoxelIndices(message.voxels, total); !error.empty()) return error;
  return ValidateStageTimes(message.num_stage_times, message.stage_times);
}

std::string VoxelCloudFromMessage(const voxel_cloud_t& message, VoxelCloud* cloud) {
  if (std::string error = ValidateVoxelCloudMessage(message); !error.empty()) return error;
  cloud->grid.origin = Vec3(message.grid_origin[0], message.grid_origin[1], message.grid_origin[2]);
  cloud->grid.voxel_size = message.voxel_size;
  cloud->grid.dims = {message.dims[0], message.dims[1], message.dims[2]};
  std::vector<size_t> order(message.voxels.size());
  std::iota(order.begin(), order.end(), size_t{0});
  if (!std::is_sorted(message.voxels.begin(), message.voxels.end())) {
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return message.voxels[a] < message.voxels[b]; });
  }
  cloud->voxels.resize(order.size());
  cloud->labels.resize(order.size());
  for (size_t i = 0; i < order.size(); ++i) {
    cloud->voxels[i] = message.voxels[order[i]];
    cloud->labels[i] = message.labels[order[i]] > 0 ? kLabelMarker : kLabelBody;
  }
  return {};
}

}  // namespace shapesense
