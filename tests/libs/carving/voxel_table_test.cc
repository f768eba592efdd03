// Tests of the internals of libs/carving: Morton order, summed-area counts,
// and the exactness of the lookup table's block bounds.
#include "libs/carving/voxel_table.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

#include "libs/carving/morton.h"
#include "libs/carving/summed_area.h"
#include "tests/libs/carving/random_scene.h"

namespace shapesense::carving_detail {
namespace {

using testing::UniformInt;

TEST(MortonTest, DecodeInvertsEncode) {
  for (uint32_t code = 0; code < (1u << 18); ++code) {
    const auto [x, y, z] = MortonDecode(code);
    ASSERT_EQ(MortonEncode(x, y, z), code);
  }
}

// Every aligned sub-block is one contiguous run of codes, and its children
// are the next level's blocks 8b .. 8b + 7.
TEST(MortonTest, AlignedSubBlocksAreContiguous) {
  for (int edge = 1; edge <= 16; edge *= 2) {
    const uint32_t voxels = edge * edge * edge;
    for (uint32_t x = 0; x < 32; ++x) {
      for (uint32_t y = 0; y < 32; ++y) {
        for (uint32_t z = 0; z < 32; ++z) {
          const uint32_t block = MortonEncode(x / edge, y / edge, z / edge);
          ASSERT_EQ(MortonEncode(x, y, z) / voxels, block);
        }
      }
    }
  }
}

PixelRect RandomRect(std::mt19937& rng) {
  PixelRect rect;
  rect.x0 = static_cast<int16_t>(UniformInt(rng, -20, 90));
  rect.y0 = static_cast<int16_t>(UniformInt(rng, -20, 70));
  rect.x1 = static_cast<int16_t>(rect.x0 + UniformInt(rng, -3, 60));
  rect.y1 = static_cast<int16_t>(rect.y0 + UniformInt(rng, -3, 50));
  return rect;
}

int32_t BruteForceCount(const cv::Mat& mask, const PixelRect& rect) {
  int32_t count = 0;
  for (int y = std::max<int>(rect.y0, 0); y <= std::min<int>(rect.y1, mask.rows - 1); ++y) {
    for (int x = std::max<int>(rect.x0, 0); x <= std::min<int>(rect.x1, mask.cols - 1); ++x) {
      count += mask.at<uint8_t>(y, x) != 0;
    }
  }
  return count;
}

TEST(SummedAreaTableTest, CountsEqualBruteForce) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    cv::Mat mask = cv::Mat::zeros(UniformInt(rng, 1, 60), UniformInt(rng, 1, 80), CV_8U);
    for (int i = UniformInt(rng, 0, 3); i > 0; --i) testing::DrawRandomEllipse(rng, 255, &mask);
    if (trial % 7 == 0) mask.setTo(255);
    if (trial % 11 == 0) mask.setTo(0);
    const SummedAreaTable sums(mask);
    EXPECT_EQ(sums.box().area() == 0, cv::countNonZero(mask) == 0);
    for (int i = 0; i < 50; ++i) {
      const PixelRect rect = RandomRect(rng);
      ASSERT_EQ(sums.Count(rect), BruteForceCount(mask, rect));
    }
    ASSERT_EQ(sums.Count(PixelRect{}), 0);
  }
}

// Each block's bounds are exactly the bounding box of its voxels' pixels, and
// its flag tells whether any voxel is outside an image.
TEST(VoxelTableTest, BlockBoundsAreExact) {
  for (int scene = 0; scene < 6; ++scene) {
    std::mt19937 rng(100 + scene);
    const std::array<int, 3> voxels = {UniformInt(rng, 9, 40), UniformInt(rng, 9, 40),
                                       UniformInt(rng, 9, 40)};
    const Rig rig = testing::RandomRig(UniformInt(rng, 1, 3), voxels, 5.0, 100.0, rng);
    const VoxelGrid grid = VoxelGrid::Covering(rig.workspace_min, rig.workspace_max, 5.0);
    const VoxelTable table(grid, rig.cameras, 1 << UniformInt(rng, 1, 5), {});
    const int cameras = table.num_cameras();
    for (const BlockLevel& level : table.levels()) {
      const int64_t block_voxels = int64_t{level.edge} * level.edge * level.edge;
      for (int64_t block = 0; block < static_cast<int64_t>(level.any_outside.size()); ++block) {
        std::vector<PixelRect> bounds(cameras);
        bool any_outside = false;
        for (int64_t slot = block * block_voxels; slot < (block + 1) * block_voxels; ++slot) {
          for (int c = 0; c < cameras; ++c) {
            const uint32_t pixel = table.Pixels(slot)[c];
            any_outside = any_outside || pixel == VoxelTable::kOutside;
            const int width = rig.cameras[c].width;
            if (pixel != VoxelTable::kOutside) bounds[c].Include(pixel % width, pixel / width);
          }
        }
        ASSERT_EQ(level.any_outside[block] != 0, any_outside);
        for (int c = 0; c < cameras; ++c) {
          const PixelRect& stored = level.rects[block * cameras + c];
          ASSERT_TRUE(stored.x0 == bounds[c].x0 && stored.y0 == bounds[c].y0 &&
                      stored.x1 == bounds[c].x1 && stored.y1 == bounds[c].y1);
        }
      }
    }
  }
}

// Slots map one to one onto the grid's voxels; padding is outside every image.
TEST(VoxelTableTest, SlotsCoverTheGridOnce) {
  std::mt19937 rng(200);
  const Rig rig = testing::RandomRig(2, {13, 17, 9}, 4.0, 300.0, rng);
  const VoxelGrid grid = VoxelGrid::Covering(rig.workspace_min, rig.workspace_max, 4.0);
  const VoxelTable table(grid, rig.cameras, 8, {});
  EXPECT_EQ(table.num_slots(), 16 * 24 * 16);
  std::set<int32_t> seen;
  for (uint32_t slot = 0; slot < table.num_slots(); ++slot) {
    const auto [x, y, z] = MortonDecode(slot % 512);
    const int64_t block = slot / 512;
    const bool padding =
        (block % 2) * 8 + x >= 13 || (block / 2 % 3) * 8 + y >= 17 || (block / 6) * 8 + z >= 9;
    if (padding) {
      EXPECT_EQ(table.Pixels(slot)[0], VoxelTable::kOutside);
      EXPECT_EQ(table.Pixels(slot)[1], VoxelTable::kOutside);
      continue;
    }
    const int32_t index = table.LinearIndex(slot);
    ASSERT_TRUE(index >= 0 && index < grid.NumVoxels());
    EXPECT_TRUE(seen.insert(index).second);
  }
  EXPECT_EQ(static_cast<int64_t>(seen.size()), grid.NumVoxels());
}

}  // namespace
}  // namespace shapesense::carving_detail
