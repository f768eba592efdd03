// Cost of the virtual rig's rendering: one VGA view of the synthetic rig's
// manipulator along the rig-sim's trajectory per iteration, on one core, by
// the exact renderer (image, background, truth mask) and by the rig-sim's
// RenderImage (the image alone, over a pooled backdrop; identical pixels
// without noise). The rig-sim renders one view per camera per trigger:
// three views at 100 Hz on one core needs a view in under 3.3 ms.
#include <benchmark/benchmark.h>
#include <malloc.h>

#include <opencv2/core/utility.hpp>

#include "libs/sim/scene_generators.h"
#include "libs/sim/trajectory.h"

namespace shapesense {
namespace {

// As the rig-sim runs (services/rig_sim/main.cc): big buffers kept in the heap.
void TuneHeap() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
  cv::setNumThreads(0);
}

Rig OneCamera() {
  Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  rig.cameras.resize(1);
  return rig;
}

TubeScene SceneAtStep(const Rig& rig, uint32_t step) {
  const TrajectoryOptions motion;
  return SceneOf(motion, rig, PoseAt(motion, 0.01 * step));
}

// Renders the trajectory's scenes one after the other with `render`.
template <class RenderOne>
void RenderAlongTheTrajectory(benchmark::State& state, RenderOne render) {
  TuneHeap();
  const Rig rig = OneCamera();
  const SceneRenderer renderer(rig);
  uint32_t step = 0;
  for (auto _ : state) {
    ++step;
    benchmark::DoNotOptimize(render(renderer, SceneAtStep(rig, step), step));
  }
  state.counters["views_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// The exact renderer: image, background and truth mask.
void BM_RenderExact(benchmark::State& state) {
  RenderAlongTheTrajectory(state,
                           [](const SceneRenderer& r, const TubeScene& scene, uint32_t seed) {
                             return r.Render(scene, RenderOptions{}, seed);
                           });
}
BENCHMARK(BM_RenderExact)->Unit(benchmark::kMillisecond);

// The rig-sim's: the image alone, the tube over a pooled backdrop.
void BM_RenderImageForTheRig(benchmark::State& state) {
  RenderAlongTheTrajectory(state,
                           [](const SceneRenderer& r, const TubeScene& scene, uint32_t seed) {
                             return r.RenderImage(0, scene, RenderOptions{}, seed);
                           });
}
BENCHMARK(BM_RenderImageForTheRig)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace shapesense

BENCHMARK_MAIN();
