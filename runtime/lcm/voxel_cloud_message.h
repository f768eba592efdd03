#pragma once

// voxel_cloud_t and the carver's VoxelCloud, both ways.
// Every message from the network is checked field by field before use: a
// malformed one yields a reason ("cam0: size: expected 921600 bytes
// (row_stride 1920 x height 480), got 1000"), never a crash. Messages built
// here from the libraries' types are always valid.
#include <string>

#include "libs/carving/voxel_grid.h"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {

// Labels on the wire: 0 body, k > 0 marker colour class k (the tape is
// class 1); in VoxelCloud: kLabelBody, kLabelMarker.

// Grid, voxels and labels; header, trigger and stage times are the caller's.
voxel_cloud_t VoxelCloudToMessage(const VoxelCloud& cloud);
// Checks dims (positive, at most 2^31 voxels), origin and voxel size
// (finite, positive), counts, and that the indices are in the grid without
// repeats. "" or the reason.
std::string ValidateVoxelCloudMessage(const voxel_cloud_t& message);
// Validates, then fills `cloud` with the voxels in ascending order.
std::string VoxelCloudFromMessage(const voxel_cloud_t& message, VoxelCloud* cloud);

}  // namespace shapesense
