#include "libs/carving/carver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "tests/libs/carving/random_scene.h"

namespace shapesense {
namespace {

using testing::Chance;
using testing::RandomRig;
using testing::Uniform;
using testing::UniformInt;

// The documented pixel of a voxel: the pixel whose square holds the
// projection of its centre, or none.
std::optional<cv::Point> PixelOf(const Camera& camera, const Vec3& centre) {
  const auto projection = camera.Project(centre);
  if (!projection || !camera.InImage(*projection)) return std::nullopt;
  return cv::Point(static_cast<int>(std::floor(projection->x() + 0.5)),
                   static_cast<int>(std::floor(projection->y() + 0.5)));
}

std::vector<Silhouette> FullSilhouettes(const Rig& rig) {
  std::vector<Silhouette> silhouettes(rig.cameras.size());
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    const Camera& camera = rig.cameras[c];
    silhouettes[c].mask = cv::Mat(camera.height, camera.width, CV_8U, cv::Scalar(255));
    silhouettes[c].labels = cv::Mat(camera.height, camera.width, CV_8U, cv::Scalar(kLabelBody));
  }
  return silhouettes;
}

bool StrictlyAscending(const std::vector<int32_t>& voxels) {
  return std::adjacent_find(voxels.begin(), voxels.end(), std::greater_equal<>()) == voxels.end();
}

CarvingOptions RandomOptions(const Rig& rig, double voxel_size, std::mt19937& rng) {
  CarvingOptions options;
  options.voxel_size = voxel_size;
  options.coarse_block = 1 << UniformInt(rng, 1, 6);
  options.min_marker_views = UniformInt(rng, 1, static_cast<int>(rig.cameras.size()));
  return options;
}

TEST(CarverTest, HierarchicalEqualsFullScanOnRandomScenes) {
  int frames_with_voxels = 0;
  int frames_with_markers = 0;
  int frames = 0;
  for (int scene = 0; scene < 40; ++scene) {
    std::mt19937 rng(1000 + scene);
    const std::array<int, 3> voxels = {UniformInt(rng, 32, 96), UniformInt(rng, 32, 96),
                                       UniformInt(rng, 32, 96)};
    const double voxel_size = Uniform(rng, 1.0, 4.0);
    const Rig rig = RandomRig(UniformInt(rng, 2, 4), voxels, voxel_size, 150.0, rng);
    const CarvingOptions options = RandomOptions(rig, voxel_size, rng);
    const Carver carver(rig, options);
    ASSERT_EQ(carver.grid().dims, voxels);
    for (int frame = 0; frame < 6; ++frame, ++frames) {
      SCOPED_TRACE("scene " + std::to_string(scene) + " frame " + std::to_string(frame));
      const std::vector<Silhouette> silhouettes = testing::RandomSilhouettes(rig, rng);
      VoxelCloud full, hierarchical;
      carver.CarveFullScan(silhouettes, &full);
      carver.CarveHierarchical(silhouettes, &hierarchical);
      ASSERT_EQ(hierarchical.voxels, full.voxels);
      ASSERT_EQ(hierarchical.labels, full.labels);
      EXPECT_TRUE(StrictlyAscending(full.voxels));
      EXPECT_EQ(full.labels.size(), full.voxels.size());
      frames_with_voxels += full.voxels.empty() ? 0 : 1;
      frames_with_markers += std::count(full.labels.begin(), full.labels.end(), kLabelMarker) > 0;
    }
  }
  // The scenes must exercise occupancy and labels, not only empty hulls.
  EXPECT_GT(frames_with_voxels, frames / 2);
  EXPECT_GT(frames_with_markers, frames / 4);
}

// With every image entirely silhouette, the occupied voxels are exactly those
// whose centres project into every image (cameras close enough to the
// workspace that some voxels are behind them or outside their view).
TEST(CarverTest, FullSilhouettesKeepExactlyTheVoxelsSeenByEveryCamera) {
  int64_t behind_a_camera = 0;
  for (int scene = 0; scene < 6; ++scene) {
    std::mt19937 rng(2000 + scene);
    const std::array<int, 3> voxels = {UniformInt(rng, 20, 50), UniformInt(rng, 20, 50),
                                       UniformInt(rng, 20, 50)};
    const double voxel_size = Uniform(rng, 3.0, 6.0);
    const Rig rig = RandomRig(UniformInt(rng, 2, 4), voxels, voxel_size, 60.0, rng);
    const Carver carver(rig, RandomOptions(rig, voxel_size, rng));
    const VoxelGrid& grid = carver.grid();
    std::vector<int32_t> expected;
    for (int32_t index = 0; index < grid.NumVoxels(); ++index) {
      bool seen = true;
      for (const Camera& camera : rig.cameras) {
        seen = seen && PixelOf(camera, grid.Center(index)).has_value();
        behind_a_camera += camera.Project(grid.Center(index)).has_value() ? 0 : 1;
      }
      if (seen) expected.push_back(index);
    }
    ASSERT_GT(expected.size(), 0u);
    ASSERT_LT(expected.size(), static_cast<size_t>(grid.NumVoxels()));
    VoxelCloud full, hierarchical;
    carver.CarveFullScan(FullSilhouettes(rig), &full);
    carver.CarveHierarchical(FullSilhouettes(rig), &hierarchical);
    EXPECT_EQ(full.voxels, expected);
    EXPECT_EQ(hierarchical.voxels, expected);
  }
  EXPECT_GT(behind_a_camera, 0);
}

// The silhouette of a ball: the projected rim of the cone of rays tangent to
// it, filled, and grown by a pixel so that every projected interior point
// rounds to a silhouette pixel.
cv::Mat BallSilhouette(const Camera& camera, const testing::Ball& ball) {
  const Vec3 towards_camera = camera.Center() - ball.centre;
  const double distance = towards_camera.norm();
  const Vec3 axis = towards_camera / distance;
  const Vec3 u = axis.unitOrthogonal();
  const Vec3 v = axis.cross(u);
  const double r = ball.radius;
  const Vec3 rim_centre = ball.centre + axis * (r * r / distance);
  const double rim_radius = r * std::sqrt(1.0 - r * r / (distance * distance));
  std::vector<cv::Point> polygon;
  for (int i = 0; i < 720; ++i) {
    const double angle = 2.0 * M_PI * i / 720;
    const Vec3 point = rim_centre + rim_radius * (std::cos(angle) * u + std::sin(angle) * v);
    const Vec2 pixel = *camera.Project(point);
    polygon.emplace_back(static_cast<int>(std::lround(pixel.x())),
                         static_cast<int>(std::lround(pixel.y())));
  }
  cv::Mat mask = cv::Mat::zeros(camera.height, camera.width, CV_8U);
  cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{polygon}, 255);
  cv::dilate(mask, mask, cv::Mat::ones(3, 3, CV_8U));
  return mask;
}

TEST(CarverTest, HullContainsTheBall) {
  for (int scene = 0; scene < 8; ++scene) {
    std::mt19937 rng(3000 + scene);
    const double voxel_size = Uniform(rng, 0.7, 2.0);
    const Rig rig = RandomRig(UniformInt(rng, 3, 4), {61, 47, 53}, voxel_size, 300.0, rng);
    CarvingOptions options = RandomOptions(rig, voxel_size, rng);
    const Carver carver(rig, options);
    const VoxelGrid& grid = carver.grid();
    const testing::Ball ball{grid.Center(30, 23, 26) + testing::RandomUnitVector(rng) * 5.0,
                             Uniform(rng, 6.0, 18.0) * voxel_size};
    std::vector<Silhouette> silhouettes(rig.cameras.size());
    for (size_t c = 0; c < rig.cameras.size(); ++c) {
      silhouettes[c].mask = BallSilhouette(rig.cameras[c], ball);
    }
    VoxelCloud cloud;
    carver.CarveHierarchical(silhouettes, &cloud);
    // Without label images nothing is a marker.
    EXPECT_EQ(std::count(cloud.labels.begin(), cloud.labels.end(), kLabelBody),
              static_cast<int64_t>(cloud.voxels.size()));
    int64_t inside = 0;
    for (int32_t index = 0; index < grid.NumVoxels(); ++index) {
      if ((grid.Center(index) - ball.centre).norm() > ball.radius) continue;
      ++inside;
      ASSERT_TRUE(std::binary_search(cloud.voxels.begin(), cloud.voxels.end(), index))
          << "scene " << scene << ": voxel " << index << " inside the ball is carved away";
    }
    // A hull from three or more views is larger than the ball, but not hugely.
    EXPECT_GT(inside, 500);
    EXPECT_LT(static_cast<double>(cloud.voxels.size()), 4.0 * static_cast<double>(inside));
  }
}

// Labels follow the rule: a marker where at least min_marker_views cameras see tape.
TEST(CarverTest, VoxelIsMarkerWhenEnoughCamerasSeeTape) {
  std::mt19937 rng(4000);
  const Rig rig = RandomRig(4, {21, 22, 23}, 4.0, 400.0, rng);
  for (int min_views = 1; min_views <= 4; ++min_views) {
    CarvingOptions options;
    options.voxel_size = 4.0;
    options.min_marker_views = min_views;
    const Carver carver(rig, options);
    for (int tape_views = 0; tape_views <= 4; ++tape_views) {
      std::vector<Silhouette> silhouettes = FullSilhouettes(rig);
      for (int c = 0; c < tape_views; ++c) silhouettes[c].labels.setTo(kLabelMarker);
      VoxelCloud full, hierarchical;
      carver.CarveFullScan(silhouettes, &full);
      carver.CarveHierarchical(silhouettes, &hierarchical);
      ASSERT_FALSE(full.voxels.empty());
      const uint8_t expected = tape_views >= min_views ? kLabelMarker : kLabelBody;
      EXPECT_EQ(full.labels, std::vector<uint8_t>(full.voxels.size(), expected));
      EXPECT_EQ(hierarchical.labels, full.labels);
    }
  }
}

TEST(CarverTest, EmptySilhouettesCarveNothing) {
  std::mt19937 rng(5000);
  const Rig rig = RandomRig(3, {40, 40, 40}, 2.0, 300.0, rng);
  CarvingOptions options;
  options.voxel_size = 2.0;
  const Carver carver(rig, options);
  std::vector<Silhouette> silhouettes = FullSilhouettes(rig);
  silhouettes[1].mask.setTo(0);
  VoxelCloud cloud;
  cloud.voxels = {1, 2, 3};  // stale content is replaced
  carver.CarveHierarchical(silhouettes, &cloud);
  EXPECT_TRUE(cloud.voxels.empty());
  carver.CarveFullScan(silhouettes, &cloud);
  EXPECT_TRUE(cloud.voxels.empty());
  EXPECT_TRUE(cloud.labels.empty());
}

TEST(CarverTest, WrongSilhouettesThrow) {
  std::mt19937 rng(6000);
  const Rig rig = RandomRig(3, {20, 20, 20}, 2.0, 300.0, rng);
  CarvingOptions options;
  options.voxel_size = 2.0;
  const Carver carver(rig, options);
  VoxelCloud cloud;
  std::vector<Silhouette> silhouettes = FullSilhouettes(rig);
  silhouettes.pop_back();
  EXPECT_THROW(carver.CarveFullScan(silhouettes, &cloud), std::invalid_argument);
  EXPECT_THROW(carver.CarveHierarchical(silhouettes, &cloud), std::invalid_argument);
  silhouettes = FullSilhouettes(rig);
  silhouettes[2].mask =
      cv::Mat::zeros(silhouettes[2].mask.rows + 1, silhouettes[2].mask.cols, CV_8U);
  EXPECT_THROW(carver.CarveFullScan(silhouettes, &cloud), std::invalid_argument);
  EXPECT_THROW(carver.CarveHierarchical(silhouettes, &cloud), std::invalid_argument);
  silhouettes = FullSilhouettes(rig);
  silhouettes[0].labels = cv::Mat::zeros(silhouettes[0].labels.size(), CV_16U);
  EXPECT_THROW(carver.CarveHierarchical(silhouettes, &cloud), std::invalid_argument);
}

// A mask that is a view into a larger image (not continuous) is carved like a copy.
TEST(CarverTest, MaskViewsAreCarvedLikeCopies) {
  std::mt19937 rng(7000);
  const Rig rig = RandomRig(2, {30, 30, 30}, 3.0, 300.0, rng);
  CarvingOptions options;
  options.voxel_size = 3.0;
  const Carver carver(rig, options);
  const std::vector<Silhouette> copies = testing::RandomSilhouettes(rig, rng);
  std::vector<Silhouette> views = copies;
  for (Silhouette& view : views) {
    cv::Mat larger = cv::Mat::zeros(view.mask.rows + 2, view.mask.cols + 3, CV_8U);
    view.mask.copyTo(larger(cv::Rect(1, 1, view.mask.cols, view.mask.rows)));
    view.mask = larger(cv::Rect(1, 1, view.mask.cols, view.mask.rows));
    ASSERT_FALSE(view.mask.isContinuous());
  }
  VoxelCloud from_copies, from_views;
  carver.CarveHierarchical(copies, &from_copies);
  carver.CarveHierarchical(views, &from_views);
  EXPECT_EQ(from_views.voxels, from_copies.voxels);
}

TEST(CarverTest, ValidateNamesTheBadKey) {
  EXPECT_EQ(CarvingOptions{}.Validate(), "");
  const auto error_of = [](auto change) {
    CarvingOptions options;
    change(options);
    return options.Validate();
  };
  EXPECT_EQ(error_of([](CarvingOptions& o) { o.voxel_size = -1; }),
            "voxel_size: expected a positive number, got -1");
  EXPECT_EQ(error_of([](CarvingOptions& o) { o.voxel_size = NAN; }).rfind("voxel_size: ", 0), 0u);
  EXPECT_EQ(
      error_of([](CarvingOptions& o) { o.min_marker_views = 0; }).rfind("min_marker_views: ", 0),
      0u);
  for (const int block : {0, 1, 3, 12, 128}) {
    EXPECT_EQ(error_of([&](CarvingOptions& o) { o.coarse_block = block; }),
              "coarse_block: expected a power of 2 from 2 to 64, got " + std::to_string(block));
  }
}

TEST(CarverTest, BadOptionsOrRigThrow) {
  std::mt19937 rng(8000);
  Rig rig = RandomRig(2, {20, 20, 20}, 2.0, 300.0, rng);
  CarvingOptions options;
  options.coarse_block = 5;
  EXPECT_THROW(Carver(rig, options), std::invalid_argument);
  rig.cameras[1].name = rig.cameras[0].name;
  EXPECT_THROW(Carver(rig, CarvingOptions{}), std::invalid_argument);
}

TEST(CarverTest, ProgressRisesToOne) {
  std::mt19937 rng(9000);
  const Rig rig = RandomRig(3, {64, 64, 64}, 2.0, 300.0, rng);
  CarvingOptions options;
  options.voxel_size = 2.0;
  options.coarse_block = 8;
  std::vector<double> fractions;
  const Carver carver(rig, options, [&](double fraction) { fractions.push_back(fraction); });
  ASSERT_GE(fractions.size(), 10u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_GE(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
}

// The table (a uint32 pixel per voxel and camera) dominates; the hierarchy's
// bounds add little.
TEST(CarverTest, MemoryIsTheTableAndAFewPercent) {
  std::mt19937 rng(10000);
  const Rig rig = RandomRig(3, {64, 64, 64}, 2.0, 300.0, rng);
  CarvingOptions options;
  options.voxel_size = 2.0;
  options.coarse_block = 16;
  const Carver carver(rig, options);
  const double table_bytes = 64.0 * 64 * 64 * 3 * sizeof(uint32_t);
  EXPECT_GE(static_cast<double>(carver.MemoryBytes()), table_bytes);
  EXPECT_LE(static_cast<double>(carver.MemoryBytes()), 1.05 * table_bytes);
}

}  // namespace
}  // namespace shapesense
