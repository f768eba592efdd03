// The replay check: identical shapes compare equal, any one coordinate
// changed is found with its size, a shape valid on one side only or with
// another number of points differs, and frame-sets on one side only are
// counted, over random shapes.
#include "clients/tools/demo/replay_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace shapesense {
namespace {

shape_t RandomShape(std::mt19937& random, int64_t seq) {
  std::uniform_real_distribution<double> coordinate(-200.0, 200.0);
  shape_t shape{};
  shape.trigger_seq = seq;
  shape.valid = true;
  shape.num_points = std::uniform_int_distribution<int>(2, 80)(random);
  for (int i = 0; i < shape.num_points; ++i) {
    shape.centerline.push_back({coordinate(random), coordinate(random), coordinate(random)});
  }
  shape.num_markers = 3;
  for (int i = 0; i < 3; ++i) {
    shape.markers.push_back({coordinate(random), coordinate(random), coordinate(random)});
    shape.marker_arc_length.push_back(50.0 * i);
    shape.marker_std_mm.push_back(0.05);
  }
  for (double& t : shape.tip) t = coordinate(random);
  return shape;
}

std::map<int64_t, shape_t> RandomShapes(std::mt19937& random, int count) {
  std::map<int64_t, shape_t> shapes;
  for (int64_t seq = 0; seq < count; ++seq) shapes[seq] = RandomShape(random, seq);
  return shapes;
}

TEST(ReplayCheckTest, TheSameShapesAreIdentical) {
  std::mt19937 random(1);
  const auto live = RandomShapes(random, 50);
  const ReplayCheck check = CompareReplay(live, live);
  EXPECT_TRUE(check.ran);
  EXPECT_EQ(check.compared, 50);
  EXPECT_EQ(check.identical, 50);
  EXPECT_EQ(check.max_difference_mm, 0.0);
  EXPECT_EQ(check.live_only + check.replay_only, 0);
}

TEST(ReplayCheckTest, AnyChangedCoordinateIsFoundWithItsSize) {
  std::mt19937 random(2);
  for (int trial = 0; trial < 100; ++trial) {
    const auto live = RandomShapes(random, 5);
    auto replayed = live;
    shape_t& changed = replayed[std::uniform_int_distribution<int64_t>(0, 4)(random)];
    const double delta = std::pow(10.0, std::uniform_real_distribution<double>(-6, 1)(random));
    const int where = std::uniform_int_distribution<int>(0, 2)(random);
    const int axis = std::uniform_int_distribution<int>(0, 2)(random);
    if (where == 0) changed.centerline[random() % changed.centerline.size()][axis] += delta;
    if (where == 1) changed.markers[random() % changed.markers.size()][axis] -= delta;
    if (where == 2) changed.tip[axis] += delta;
    const ReplayCheck check = CompareReplay(live, replayed);
    EXPECT_EQ(check.identical, 4);
    EXPECT_NEAR(check.max_difference_mm, delta, 1e-12 + delta * 1e-9);
  }
}

TEST(ReplayCheckTest, ValidityOrPointCountChangedDiffers) {
  std::mt19937 random(3);
  const shape_t shape = RandomShape(random, 0);
  shape_t invalid = shape;
  invalid.valid = false;
  EXPECT_TRUE(std::isinf(ShapeDifference(shape, invalid)));
  shape_t shorter = shape;
  shorter.centerline.pop_back();
  EXPECT_TRUE(std::isinf(ShapeDifference(shape, shorter)));
  EXPECT_EQ(ShapeDifference(shape, shape), 0.0);
}

TEST(ReplayCheckTest, SetsOnOneSideOnlyAreCounted) {
  std::mt19937 random(4);
  auto live = RandomShapes(random, 30);
  auto replayed = live;
  int removed_live = 0, removed_replayed = 0;
  for (int64_t seq = 0; seq < 30; ++seq) {
    const int side = std::uniform_int_distribution<int>(0, 3)(random);
    if (side == 0) removed_live += static_cast<int>(live.erase(seq));
    if (side == 1) removed_replayed += static_cast<int>(replayed.erase(seq));
  }
  const ReplayCheck check = CompareReplay(live, replayed);
  EXPECT_EQ(check.live_only, removed_replayed);
  EXPECT_EQ(check.replay_only, removed_live);
  EXPECT_EQ(check.compared, 30 - removed_live - removed_replayed);
  EXPECT_EQ(check.identical, check.compared);
}

}  // namespace
}  // namespace shapesense
