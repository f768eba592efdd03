// The silhouette's cost per 640×480 view, and what sending it to the shape
// service adds: extraction, compaction (carving service) and expansion
// (shape service), one core. Counters: the mask's pixels, and the compact
// form's size on the wire (runs at 6 bytes, a byte per band pixel).
#include <benchmark/benchmark.h>

#include "libs/silhouette/compact_silhouette.h"
#include "libs/silhouette/silhouette.h"
#include "tests/libs/silhouette/synthetic_frame.h"

namespace shapesense {
namespace {

const testing::SyntheticFrame& Frame() {
  static const testing::SyntheticFrame frame = testing::MakeFrame(testing::FrameSpec{});
  return frame;
}

Silhouette Extracted() {
  Silhouette silhouette;
  SilhouetteExtractor(SilhouetteOptions{}).Extract(Frame().image, Frame().background, &silhouette);
  return silhouette;
}

void BM_Extract(benchmark::State& state) {
  const SilhouetteExtractor extractor(SilhouetteOptions{});
  Silhouette silhouette;
  for (auto _ : state) extractor.Extract(Frame().image, Frame().background, &silhouette);
  state.counters["mask_px"] = static_cast<double>(silhouette.area);
}
BENCHMARK(BM_Extract)->Unit(benchmark::kMicrosecond);

// The tape labels cost per mask pixel: a tube 40 px wide with six bands (a
// camera close to the tube) puts nearly four times the default frame's pixels in the mask.
void BM_ExtractWideTube(benchmark::State& state) {
  testing::FrameSpec spec;
  spec.tube_thickness = 40;
  spec.tape_bands = 6;
  const testing::SyntheticFrame frame = testing::MakeFrame(spec);
  const SilhouetteExtractor extractor(SilhouetteOptions{});
  Silhouette silhouette;
  for (auto _ : state) extractor.Extract(frame.image, frame.background, &silhouette);
  state.counters["mask_px"] = static_cast<double>(silhouette.area);
}
BENCHMARK(BM_ExtractWideTube)->Unit(benchmark::kMicrosecond);

void BM_Compact(benchmark::State& state) {
  const Silhouette silhouette = Extracted();
  CompactSilhouette compact;
  CompactScratch scratch;
  for (auto _ : state) Compact(silhouette, &compact, &scratch);
  state.counters["bytes"] =
      static_cast<double>(6 * (compact.mask.size() + compact.markers.size() + compact.band.size()) +
                          compact.band_difference.size());
}
BENCHMARK(BM_Compact)->Unit(benchmark::kMicrosecond);

void BM_Expand(benchmark::State& state) {
  CompactSilhouette compact;
  CompactScratch scratch;
  Compact(Extracted(), &compact, &scratch);
  Silhouette expanded;
  for (auto _ : state) Expand(compact, &expanded);
}
BENCHMARK(BM_Expand)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace shapesense

BENCHMARK_MAIN();
