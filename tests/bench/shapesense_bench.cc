// Throughput and memory of the sensing chain, in one run on one core:
// frame-sets per second for silhouettes (3 × 640×480), carving at 256³ (full
// lookup-table scan and hierarchical, and their ratio), shape estimation and
// the whole chain; peak memory at 256³ (1 mm) and 512³ (0.5 mm).
// Targets (issue 2): chain ≥ 500 frame-sets/s at 256³, hierarchical ≥ 50× the
// full scan, ≤ 300 MB at 256³. Prints figures; asserts nothing (noisy machines).
#include <sched.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <string>

#include "libs/sim/scene_generators.h"
#include "runtime/sensing_pipeline.h"

namespace shapesense {
namespace {

using Clock = std::chrono::steady_clock;

struct Scenes {
  std::vector<std::vector<cv::Mat>> images;  // per scene, per camera
  std::vector<cv::Mat> backgrounds;
};

Scenes RenderScenes(const Rig& rig, int count) {
  Scenes scenes;
  for (int i = 0; i < count; ++i) {
    const TubeScene scene = RandomScene(rig, 500 + static_cast<uint32_t>(i), 2.6, 3);
    const std::vector<RenderedView> views =
        RenderScene(rig, scene, RenderOptions{}, static_cast<uint32_t>(i));
    std::vector<cv::Mat> images;
    for (const RenderedView& view : views) images.push_back(view.image);
    scenes.images.push_back(images);
    if (i == 0) {
      for (const RenderedView& view : views) scenes.backgrounds.push_back(view.background);
    }
  }
  return scenes;
}

double ThreadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// Wall-clock rate of the last Rate() call, for the record next to the CPU rate.
double g_last_wall_rate = 0.0;

// Runs `work(i)` for about `seconds` of this thread's CPU time (at least
// `min_runs` times); returns calls per CPU-second of one core. CPU time, not
// wall time, so that other processes on a busy machine do not count.
template <class Work>
double Rate(double seconds, int min_runs, Work work) {
  const auto wall_start = Clock::now();
  const double start = ThreadCpuSeconds();
  int runs = 0;
  double elapsed = 0.0;
  while (runs < min_runs || elapsed < seconds) {
    work(runs++);
    elapsed = ThreadCpuSeconds() - start;
  }
  g_last_wall_rate = runs / std::chrono::duration<double>(Clock::now() - wall_start).count();
  return runs / elapsed;
}

double PeakResidentMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void PinToOneCore() {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(0, &set);
  if (sched_setaffinity(0, sizeof(set), &set) != 0) std::printf("(could not pin to one core)\n");
}

struct StageRates {
  double silhouettes = 0.0;
  double full_scan = 0.0;
  double hierarchical = 0.0;
  double shape = 0.0;
  double chain = 0.0;
  double chain_wall = 0.0;  // wall clock: lower when other processes share the core
};

StageRates MeasureStages(const Rig& rig, const Scenes& scenes, const SensingPipeline& pipeline,
                         const PipelineOptions& options, bool with_full_scan) {
  const size_t n = scenes.images.size();
  std::vector<FrameResult> results(n);
  for (size_t i = 0; i < n; ++i) pipeline.Process(scenes.images[i], &results[i]);
  StageRates rates;
  const SilhouetteExtractor extractor(options.silhouette);
  std::vector<Silhouette> silhouettes(rig.cameras.size());
  rates.silhouettes = Rate(1.0, 20, [&](int run) {
    const auto& images = scenes.images[static_cast<size_t>(run) % n];
    for (size_t c = 0; c < images.size(); ++c)
      extractor.Extract(images[c], scenes.backgrounds[c], &silhouettes[c]);
  });
  VoxelCloud cloud;
  if (with_full_scan) {
    rates.full_scan = Rate(2.0, 3, [&](int run) {
      pipeline.carver().CarveFullScan(results[static_cast<size_t>(run) % n].silhouettes, &cloud);
    });
  }
  rates.hierarchical = Rate(1.0, 20, [&](int run) {
    pipeline.carver().CarveHierarchical(results[static_cast<size_t>(run) % n].silhouettes, &cloud);
  });
  const ShapeEstimator estimator(rig, options.shape);
  rates.shape = Rate(1.0, 20, [&](int run) {
    const FrameResult& r = results[static_cast<size_t>(run) % n];
    const ShapeEstimate shape = estimator.Estimate(r.cloud, r.silhouettes);
    if (!shape.valid) std::printf("  (scene %d not measured: %s)\n", run, shape.error.c_str());
  });
  FrameResult result;
  rates.chain = Rate(2.0, 20, [&](int run) {
    pipeline.Process(scenes.images[static_cast<size_t>(run) % n], &result);
  });
  rates.chain_wall = g_last_wall_rate;
  return rates;
}

void PrintRates(const StageRates& r) {
  std::printf("  silhouettes (3 x 640x480) %9.1f frame-sets/s  (%.3f ms)\n", r.silhouettes,
              1e3 / r.silhouettes);
  if (r.full_scan > 0) {
    std::printf("  carving, full table scan  %9.1f frame-sets/s  (%.3f ms)\n", r.full_scan,
                1e3 / r.full_scan);
  }
  std::printf("  carving, hierarchical     %9.1f frame-sets/s  (%.3f ms)\n", r.hierarchical,
              1e3 / r.hierarchical);
  if (r.full_scan > 0)
    std::printf("  hierarchical / full scan  %9.1f x\n", r.hierarchical / r.full_scan);
  std::printf("  shape estimation          %9.1f frame-sets/s  (%.3f ms)\n", r.shape,
              1e3 / r.shape);
  std::printf("  whole chain               %9.1f frame-sets/s  (%.3f ms)\n", r.chain,
              1e3 / r.chain);
  std::printf(
      "  whole chain, wall clock   %9.1f frame-sets/s  (other load on the machine counts)\n",
      r.chain_wall);
}

void RunAt(const Rig& rig, const Scenes& scenes, double voxel_size, bool with_full_scan) {
  PipelineOptions options;
  options.carving.voxel_size = voxel_size;
  const auto start = Clock::now();
  const SensingPipeline pipeline(rig, options, scenes.backgrounds);
  const double build_s = std::chrono::duration<double>(Clock::now() - start).count();
  const VoxelGrid& grid = pipeline.carver().grid();
  std::printf(
      "\n%d x %d x %d voxels of %.2f mm, %zu cameras (lookup table built in %.1f s, %.0f MB)\n",
      grid.dims[0], grid.dims[1], grid.dims[2], voxel_size, rig.cameras.size(), build_s,
      static_cast<double>(pipeline.carver().MemoryBytes()) / 1e6);
  PrintRates(MeasureStages(rig, scenes, pipeline, options, with_full_scan));
  std::printf("  peak resident memory so far: %.0f MB\n", PeakResidentMb());
}

}  // namespace
}  // namespace shapesense

int main(int argc, char** argv) {
  using namespace shapesense;  // NOLINT(google-build-using-namespace): a main
  const bool skip_512 = argc > 1 && std::strcmp(argv[1], "--no-512") == 0;
  PinToOneCore();
  SyntheticRigOptions rig_options;
  rig_options.seed = 11;
  const Rig rig = MakeSyntheticRig(rig_options);
  const Scenes scenes = RenderScenes(rig, 8);
  std::printf(
      "shapesense_bench: one core, 8 rendered scenes (random arcs and S-curves, bends to 150 "
      "deg)\n"
      "rates: per second of this thread's CPU time on one pinned core\n");
  RunAt(rig, scenes, 1.0, /*with_full_scan=*/true);
  if (!skip_512) RunAt(rig, scenes, 0.5, /*with_full_scan=*/false);
  return 0;
}
