// Voxel carving at the reference's size: 256³ voxels of 1 mm, three 640×480
// cameras, a bent tube of radius 3 mm and length 160 mm (silhouettes ~10 px
// wide). Full scan against the hierarchical search, per frame-set; the table
// build time and the memory are reported as counters.

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "libs/carving/carver.h"
#include "tests/libs/camera/test_rig.h"

namespace shapesense {
namespace {

constexpr double kTubeRadius = 3.0;    // mm
constexpr double kTubeLength = 160.0;  // mm
constexpr int kPoses = 16;

Rig ReferenceRig() {
  Rig rig;
  for (int i = 0; i < 3; ++i) {
    rig.cameras.push_back(
        testing::DistortedCamera("cam" + std::to_string(i), 2.0 * std::numbers::pi * i / 3.0));
  }
  rig.workspace_min = Vec3::Constant(-128.0);
  rig.workspace_max = Vec3::Constant(128.0);
  rig.base_point = Vec3(0.0, 0.0, -100.0);
  return rig;
}

// A constant-curvature centreline from the base, up +z, bending towards
// `bend_direction` (radians about z) through `bend_angle`, sampled every 0.5 mm.
Polyline BentCentreline(const Vec3& base, double bend_direction, double bend_angle) {
  const Vec3 towards(std::cos(bend_direction), std::sin(bend_direction), 0.0);
  Polyline points;
  for (double s = 0.0; s <= kTubeLength; s += 0.5) {
    const double angle = bend_angle * s / kTubeLength;
    const double radius = kTubeLength / bend_angle;
    points.push_back(base + towards * radius * (1.0 - std::cos(angle)) +
                     Vec3::UnitZ() * radius * std::sin(angle));
  }
  return points;
}

// The tube's silhouette in one camera, drawn as a chain of thick segments of
// the projected width; tape bands at two places are labelled as markers.
Silhouette DrawTube(const Camera& camera, const Polyline& centreline) {
  Silhouette silhouette;
  silhouette.mask = cv::Mat::zeros(camera.height, camera.width, CV_8U);
  silhouette.labels = cv::Mat::zeros(camera.height, camera.width, CV_8U);
  for (size_t i = 1; i < centreline.size(); ++i) {
    const auto a = camera.Project(centreline[i - 1]);
    const auto b = camera.Project(centreline[i]);
    if (!a || !b) continue;
    const double depth = (camera.cam_from_world * centreline[i]).z();
    const int width =
        static_cast<int>(std::lround(2.0 * camera.camera_matrix(0, 0) * kTubeRadius / depth));
    const cv::Point pa(static_cast<int>(std::lround(a->x())),
                       static_cast<int>(std::lround(a->y())));
    const cv::Point pb(static_cast<int>(std::lround(b->x())),
                       static_cast<int>(std::lround(b->y())));
    const double s = 0.5 * static_cast<double>(i);
    const bool tape = std::abs(s - 60.0) < 3.0 || std::abs(s - 150.0) < 3.0;
    cv::line(silhouette.mask, pa, pb, 255, width);
    cv::line(silhouette.labels, pa, pb, tape ? kLabelMarker : kLabelBody, width);
  }
  return silhouette;
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct BenchScene {
  Rig rig = ReferenceRig();
  std::vector<std::vector<Silhouette>> frames;  // one per pose
  std::unique_ptr<Carver> carver;
  int coarse_block = 0;
  double build_seconds = 0.0;
};

BenchScene& Scene(int coarse_block) {
  static BenchScene scene;
  if (scene.frames.empty()) {
    for (int pose = 0; pose < kPoses; ++pose) {
      const Polyline centreline =
          BentCentreline(scene.rig.base_point, 0.4 * pose, 0.3 + 0.1 * pose);
      std::vector<Silhouette>& frame = scene.frames.emplace_back();
      for (const Camera& camera : scene.rig.cameras) frame.push_back(DrawTube(camera, centreline));
    }
  }
  if (scene.coarse_block != coarse_block) {
    scene.carver.reset();  // one table at a time
    CarvingOptions options;
    options.coarse_block = coarse_block;
    const auto start = std::chrono::steady_clock::now();
    scene.carver = std::make_unique<Carver>(scene.rig, options);
    scene.build_seconds = SecondsSince(start);
    scene.coarse_block = coarse_block;
  }
  return scene;
}

void ReportCounters(const BenchScene& scene, double voxels, benchmark::State& state) {
  state.counters["table_build_s"] = scene.build_seconds;
  state.counters["memory_MB"] = static_cast<double>(scene.carver->MemoryBytes()) / 1e6;
  state.counters["voxels"] = voxels;
}

void BM_CarveFullScan(benchmark::State& state) {
  const BenchScene& scene = Scene(CarvingOptions{}.coarse_block);
  VoxelCloud cloud;
  size_t frame = 0;
  double voxels = 0.0;
  for (auto _ : state) {
    scene.carver->CarveFullScan(scene.frames[frame++ % kPoses], &cloud);
    benchmark::DoNotOptimize(cloud.voxels.data());
    voxels += static_cast<double>(cloud.voxels.size());
  }
  ReportCounters(scene, voxels / static_cast<double>(state.iterations()), state);
}
BENCHMARK(BM_CarveFullScan)->Unit(benchmark::kMillisecond);

// Runs both searches on every pose; returns the mean full-scan time, s, or
// a negative number when the searches disagree (the benchmark would then
// measure nothing).
double CheckedFullScanSeconds(const BenchScene& scene) {
  double full_scan_seconds = 0.0;
  for (const std::vector<Silhouette>& frame : scene.frames) {
    VoxelCloud full, hierarchical;
    const auto start = std::chrono::steady_clock::now();
    scene.carver->CarveFullScan(frame, &full);
    full_scan_seconds += SecondsSince(start);
    scene.carver->CarveHierarchical(frame, &hierarchical);
    if (full.voxels != hierarchical.voxels || full.labels != hierarchical.labels) return -1.0;
  }
  return full_scan_seconds / kPoses;
}

// Arguments: coarse block edge; poses cycled through (16: caches as cold as
// a fast-moving tube makes them; 1: one pose over and over, warm caches).
// speedup: the full scan's wall time over the hierarchical search's.
void BM_CarveHierarchical(benchmark::State& state) {
  const BenchScene& scene = Scene(static_cast<int>(state.range(0)));
  const size_t poses = static_cast<size_t>(state.range(1));
  const double full_scan_seconds = CheckedFullScanSeconds(scene);
  if (full_scan_seconds < 0.0) {
    state.SkipWithError("hierarchical search differs from the full scan");
    return;
  }
  VoxelCloud cloud;
  size_t frame = 0;
  double voxels = 0.0;
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) {
    scene.carver->CarveHierarchical(scene.frames[frame++ % poses], &cloud);
    benchmark::DoNotOptimize(cloud.voxels.data());
    voxels += static_cast<double>(cloud.voxels.size());
  }
  const double iterations = static_cast<double>(state.iterations());
  ReportCounters(scene, voxels / iterations, state);
  state.counters["speedup"] = full_scan_seconds / (SecondsSince(start) / iterations);
}
BENCHMARK(BM_CarveHierarchical)
    ->ArgNames({"block", "poses"})
    ->Args({32, kPoses})
    ->Args({32, 1})
    ->Args({8, kPoses})
    ->Args({16, kPoses})
    ->Args({64, kPoses})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace shapesense

BENCHMARK_MAIN();
