#pragma once

// The voxel→pixel lookup table of a rig and the pixel bounds of the blocks of
// the hierarchical search. Internal to libs/carving.

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/pixel_rect.h"
#include "libs/carving/voxel_grid.h"

namespace shapesense::carving_detail {

// The pixel bounds of every block of one edge length, in table order.
struct BlockLevel {
  int edge = 0;                      // voxels
  std::vector<PixelRect> rects;      // [block * num_cameras + camera]: bounds of the table pixels
  std::vector<uint8_t> any_outside;  // [block]: some voxel is outside some image
};

// Voxels are stored block-major: coarse blocks of coarse_block³ voxels in the
// order of their block coordinates (x fastest), the voxels of a block in
// Morton order, so every block of every level is a contiguous run of "slots".
// A grid that is not a whole number of coarse blocks is padded; padding slots
// are outside every image. Each slot holds one pixel index (y * width + x)
// per camera, cameras interleaved, or kOutside.
//
// A voxel's pixel is floor(Camera::Project(centre) + 0.5) per coordinate:
// the pixel whose square holds the projection, the same rule as
// Camera::InImage. A centre behind a camera or outside its image is kOutside.
class VoxelTable {
 public:
  static constexpr uint32_t kOutside = 0xffffffffu;
  // Edge of the finest level with stored bounds; its blocks' voxels are
  // tested one by one.
  static constexpr int kLeafEdge = 4;

  // `progress` (may be empty) is called with the fraction done.
  VoxelTable(const VoxelGrid& grid, const std::vector<Camera>& cameras, int coarse_block,
             const std::function<void(double)>& progress);

  int num_cameras() const { return num_cameras_; }
  int64_t num_slots() const { return num_slots_; }
  int64_t num_coarse_blocks() const { return num_slots_ >> (3 * log2_block_); }
  // The num_cameras() pixel indices of a slot.
  const uint32_t* Pixels(int64_t slot) const { return pixels_.get() + slot * num_cameras_; }
  // Coarsest level first; the last is the leaf level.
  const std::vector<BlockLevel>& levels() const { return levels_; }
  // Linear grid index of a slot that is not padding.
  int32_t LinearIndex(uint32_t slot) const {
    return block_offsets_[slot >> (3 * log2_block_)] +
           local_offsets_[slot & static_cast<uint32_t>(block_voxels_ - 1)];
  }
  size_t MemoryBytes() const;

 private:
  void AllocateLevels(int coarse_block);
  std::array<int, 3> CoarseBlockCoordinates(int64_t block) const;
  void FillCoarseBlock(int64_t block, const std::vector<Camera>& cameras);
  uint32_t PixelOf(const Camera& camera, const Vec3& centre, PixelRect* bounds) const;
  void BuildUpperLevels();
  void BuildIndexOffsets();

  VoxelGrid grid_;
  int num_cameras_ = 0;
  int log2_block_ = 0;
  int64_t block_voxels_ = 0;
  std::array<int, 3> num_blocks_ = {0, 0, 0};
  int64_t num_slots_ = 0;
  std::unique_ptr<uint32_t[]> pixels_;
  std::vector<BlockLevel> levels_;
  // LinearIndex = block_offsets_[coarse block] + local_offsets_[Morton code].
  std::vector<int32_t> block_offsets_;
  std::vector<int32_t> local_offsets_;
};

}  // namespace shapesense::carving_detail
