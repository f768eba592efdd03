#include "libs/carving/voxel_grid.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace shapesense {
namespace {

VoxelGrid RandomGrid(std::mt19937& rng) {
  std::uniform_int_distribution<int> dim(1, 300);
  std::uniform_real_distribution<double> coordinate(-500.0, 500.0);
  VoxelGrid grid;
  grid.origin = Vec3(coordinate(rng), coordinate(rng), coordinate(rng));
  grid.voxel_size = std::uniform_real_distribution<double>(0.1, 5.0)(rng);
  grid.dims = {dim(rng), dim(rng), dim(rng)};
  return grid;
}

TEST(VoxelGridTest, IndexAndCoordinatesRoundTrip) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 200; ++trial) {
    const VoxelGrid grid = RandomGrid(rng);
    std::uniform_int_distribution<int64_t> any_index(0, grid.NumVoxels() - 1);
    for (int i = 0; i < 50; ++i) {
      const int64_t index = any_index(rng);
      const auto [x, y, z] = grid.Coordinates(index);
      ASSERT_TRUE(x >= 0 && y >= 0 && z >= 0);
      ASSERT_TRUE(x < grid.dims[0] && y < grid.dims[1] && z < grid.dims[2]);
      EXPECT_EQ(grid.Index(x, y, z), index);
      EXPECT_EQ(grid.Center(index), grid.Center(x, y, z));
    }
  }
}

TEST(VoxelGridTest, CentresAreOneVoxelApartAlongEachAxis) {
  std::mt19937 rng(2);
  const VoxelGrid grid = RandomGrid(rng);
  EXPECT_EQ(grid.Center(0, 0, 0), grid.origin);
  const Vec3 c = grid.Center(1, 2, 3);
  EXPECT_NEAR((grid.Center(2, 2, 3) - c - Vec3::UnitX() * grid.voxel_size).norm(), 0.0, 1e-9);
  EXPECT_NEAR((grid.Center(1, 3, 3) - c - Vec3::UnitY() * grid.voxel_size).norm(), 0.0, 1e-9);
  EXPECT_NEAR((grid.Center(1, 2, 4) - c - Vec3::UnitZ() * grid.voxel_size).norm(), 0.0, 1e-9);
}

TEST(VoxelGridTest, CoveringTilesTheBox) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coordinate(-300.0, 300.0);
  std::uniform_real_distribution<double> size(0.2, 7.0);
  for (int trial = 0; trial < 500; ++trial) {
    Vec3 min(coordinate(rng), coordinate(rng), coordinate(rng));
    Vec3 max = min + Vec3(size(rng), size(rng), size(rng)) * 20.0;
    const double voxel_size = size(rng);
    const VoxelGrid grid = VoxelGrid::Covering(min, max, voxel_size);
    EXPECT_EQ(grid.voxel_size, voxel_size);
    for (int axis = 0; axis < 3; ++axis) {
      const double low = grid.origin[axis] - 0.5 * voxel_size;
      const double high = low + grid.dims[axis] * voxel_size;
      EXPECT_NEAR(low, min[axis], 1e-9);
      EXPECT_GE(high, max[axis] - 1e-6);        // covers the box...
      EXPECT_LT(high, max[axis] + voxel_size);  // ...with less than a voxel to spare
    }
  }
}

TEST(VoxelGridTest, CoveringAWholeNumberOfVoxelsAddsNone) {
  EXPECT_EQ(VoxelGrid::Covering(Vec3::Constant(-128), Vec3::Constant(128), 1.0).dims,
            (std::array<int, 3>{256, 256, 256}));
  EXPECT_EQ(VoxelGrid::Covering(Vec3(-0.3, 0, 0), Vec3(0.3, 0.7, 0.1), 0.1).dims,
            (std::array<int, 3>{6, 7, 1}));
}

TEST(VoxelGridTest, CoveringRejectsAnEmptyBoxOrBadSize) {
  EXPECT_THROW(VoxelGrid::Covering(Vec3::Zero(), Vec3(1, 0, 1), 0.1), std::invalid_argument);
  EXPECT_THROW(VoxelGrid::Covering(Vec3::Zero(), Vec3::Ones(), 0.0), std::invalid_argument);
  EXPECT_THROW(VoxelGrid::Covering(Vec3::Zero(), Vec3::Ones(), -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
