#include "libs/carving/voxel_table.h"

#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "libs/carving/morton.h"

namespace shapesense::carving_detail {
namespace {

// Largest image side the int16 block bounds can hold.
constexpr int kMaxImageSide = std::numeric_limits<int16_t>::max();

void CheckImageSizes(const std::vector<Camera>& cameras) {
  for (const Camera& camera : cameras) {
    if (camera.width > kMaxImageSide || camera.height > kMaxImageSide) {
      throw std::invalid_argument("camera '" + camera.name + "': images larger than " +
                                  std::to_string(kMaxImageSide) + " px a side are not supported");
    }
  }
}

// Calls `progress` each time the fraction done passes another percent.
class ProgressReporter {
 public:
  explicit ProgressReporter(const std::function<void(double)>& progress) : progress_(progress) {}
  void Report(double fraction) {
    if (!progress_ || (fraction < last_ + 0.01 && fraction < 1.0)) return;
    last_ = fraction;
    progress_(fraction);
  }

 private:
  const std::function<void(double)>& progress_;
  double last_ = -1.0;
};

}  // namespace

VoxelTable::VoxelTable(const VoxelGrid& grid, const std::vector<Camera>& cameras, int coarse_block,
                       const std::function<void(double)>& progress)
    : grid_(grid),
      num_cameras_(static_cast<int>(cameras.size())),
      log2_block_(std::countr_zero(static_cast<unsigned>(coarse_block))),
      block_voxels_(int64_t{1} << (3 * log2_block_)) {
  CheckImageSizes(cameras);
  for (int axis = 0; axis < 3; ++axis) {
    num_blocks_[axis] = (grid.dims[axis] + coarse_block - 1) / coarse_block;
  }
  num_slots_ = int64_t{num_blocks_[0]} * num_blocks_[1] * num_blocks_[2] * block_voxels_;
  if (grid.NumVoxels() > std::numeric_limits<int32_t>::max() ||
      num_slots_ > int64_t{std::numeric_limits<uint32_t>::max()}) {
    throw std::invalid_argument("the voxel grid is too large (more than 2^31 voxels)");
  }
  pixels_ = std::make_unique_for_overwrite<uint32_t[]>(num_slots_ * num_cameras_);
  AllocateLevels(coarse_block);
  ProgressReporter reporter(progress);
  for (int64_t block = 0; block < num_coarse_blocks(); ++block) {
    FillCoarseBlock(block, cameras);
    reporter.Report(0.95 * static_cast<double>(block + 1) /
                    static_cast<double>(num_coarse_blocks()));
  }
  BuildUpperLevels();
  BuildIndexOffsets();
  reporter.Report(1.0);
}

// Levels from the coarse blocks down to the leaves, bounds empty, flags clear.
void VoxelTable::AllocateLevels(int coarse_block) {
  for (int edge = coarse_block; edge >= std::min(coarse_block, kLeafEdge); edge /= 2) {
    BlockLevel& level = levels_.emplace_back();
    level.edge = edge;
    const int64_t blocks = num_slots_ / (int64_t{edge} * edge * edge);
    level.rects.assign(blocks * num_cameras_, PixelRect{});
    level.any_outside.assign(blocks, 0);
  }
}

std::array<int, 3> VoxelTable::CoarseBlockCoordinates(int64_t block) const {
  const int64_t x = block % num_blocks_[0];
  const int64_t yz = block / num_blocks_[0];
  return {static_cast<int>(x), static_cast<int>(yz % num_blocks_[1]),
          static_cast<int>(yz / num_blocks_[1])};
}

// Fills the slots of one coarse block and the leaf bounds inside it.
void VoxelTable::FillCoarseBlock(int64_t block, const std::vector<Camera>& cameras) {
  const std::array<int, 3> corner = CoarseBlockCoordinates(block);
  BlockLevel& leaf = levels_.back();
  const int leaf_shift = 3 * std::countr_zero(static_cast<unsigned>(leaf.edge));
  for (int64_t code = 0; code < block_voxels_; ++code) {
    const int64_t slot = block * block_voxels_ + code;
    const int64_t leaf_block = slot >> leaf_shift;
    uint32_t* pixels = pixels_.get() + slot * num_cameras_;
    const std::array<int, 3> local = MortonDecode(static_cast<uint32_t>(code));
    std::array<int, 3> voxel{};
    bool padding = false;
    for (int axis = 0; axis < 3; ++axis) {
      voxel[axis] = (corner[axis] << log2_block_) + local[axis];
      padding = padding || voxel[axis] >= grid_.dims[axis];
    }
    const Vec3 centre = grid_.Center(voxel[0], voxel[1], voxel[2]);
    for (int c = 0; c < num_cameras_; ++c) {
      pixels[c] = padding ? kOutside
                          : PixelOf(cameras[c], centre, &leaf.rects[leaf_block * num_cameras_ + c]);
      if (pixels[c] == kOutside) leaf.any_outside[leaf_block] = 1;
    }
  }
}

uint32_t VoxelTable::PixelOf(const Camera& camera, const Vec3& centre, PixelRect* bounds) const {
  const std::optional<Vec2> projection = camera.Project(centre);
  if (!projection) return kOutside;
  const double u = std::floor(projection->x() + 0.5);
  const double v = std::floor(projection->y() + 0.5);
  // Written so that a NaN projection also counts as outside.
  if (!(u >= 0.0 && v >= 0.0 && u < camera.width && v < camera.height)) return kOutside;
  const int x = static_cast<int>(u);
  const int y = static_cast<int>(v);
  bounds->Include(x, y);
  return static_cast<uint32_t>(y) * static_cast<uint32_t>(camera.width) + static_cast<uint32_t>(x);
}

// Each block's bounds are the union of its eight children's, so they are
// exact by construction.
void VoxelTable::BuildUpperLevels() {
  for (size_t i = levels_.size() - 1; i-- > 0;) {
    BlockLevel& parent = levels_[i];
    const BlockLevel& children = levels_[i + 1];
    for (size_t block = 0; block < parent.any_outside.size(); ++block) {
      for (size_t child = 8 * block; child < 8 * block + 8; ++child) {
        parent.any_outside[block] |= children.any_outside[child];
        for (int c = 0; c < num_cameras_; ++c) {
          parent.rects[block * num_cameras_ + c].Include(children.rects[child * num_cameras_ + c]);
        }
      }
    }
  }
}

// Slot → linear index through two small tables, so that writing the occupied
// voxels costs no Morton decoding or division.
void VoxelTable::BuildIndexOffsets() {
  for (int64_t block = 0; block < num_coarse_blocks(); ++block) {
    const std::array<int, 3> corner = CoarseBlockCoordinates(block);
    block_offsets_.push_back(static_cast<int32_t>(
        grid_.Index(corner[0] << log2_block_, corner[1] << log2_block_, corner[2] << log2_block_)));
  }
  for (uint32_t code = 0; code < block_voxels_; ++code) {
    const auto [x, y, z] = MortonDecode(code);
    // Codes beyond the grid are only ever padding, which LinearIndex is never
    // asked about (and whose offset might not fit).
    const bool in_grid = x < grid_.dims[0] && y < grid_.dims[1] && z < grid_.dims[2];
    local_offsets_.push_back(in_grid ? static_cast<int32_t>(grid_.Index(x, y, z)) : 0);
  }
}

size_t VoxelTable::MemoryBytes() const {
  size_t bytes = sizeof(uint32_t) * static_cast<size_t>(num_slots_ * num_cameras_);
  for (const BlockLevel& level : levels_) {
    bytes += level.rects.size() * sizeof(PixelRect) + level.any_outside.size();
  }
  bytes += sizeof(int32_t) * (block_offsets_.size() + local_offsets_.size());
  return bytes;
}

}  // namespace shapesense::carving_detail
