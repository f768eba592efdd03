#include "tests/bench/latency_stats.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>

#include "runtime/lcm/stage_times.h"

namespace shapesense::bench {
namespace {

// Points in time of one frame-set, µs on the host clock, in pipeline order.
struct Timeline {
  int64_t trigger = 0;
  int64_t set_complete = 0;  // carving service: LCM's receive time of the set's last image
  // The silhouettes the complete set still waited for (those of its last
  // image, the others were extracted as their images arrived).
  int64_t silhouette_start = 0;
  int64_t silhouette_end = 0;
  int64_t carving_end = 0;  // voxel cloud built (publishing follows)
  int64_t shape_start = 0;  // shape service's worker took the cloud
  int64_t shape_end = 0;
  int64_t received = 0;
};

std::optional<Timeline> TimelineOf(const ShapeSample& sample) {
  const stage_time_t* transport = FindStageTime(sample.stages, "transport");
  const stage_time_t* silhouette = FindStageTime(sample.stages, "silhouette");
  const stage_time_t* carving = FindStageTime(sample.stages, "carving");
  const stage_time_t* shape = FindStageTime(sample.stages, "shape");
  if (!transport || !silhouette || !carving || !shape) return std::nullopt;
  Timeline t;
  t.trigger = sample.trigger_utime;
  t.set_complete = transport->end_utime;
  t.silhouette_start = silhouette->end_utime - silhouette->duration_us;
  t.silhouette_end = silhouette->end_utime;
  t.carving_end = carving->end_utime;
  t.shape_start = shape->end_utime - shape->duration_us;
  t.shape_end = shape->end_utime;
  t.received = sample.receive_utime;
  return t;
}

double Ms(int64_t from, int64_t to) { return static_cast<double>(to - from) * 1e-3; }

void PrintRow(const char* name, const Percentiles& p) {
  std::printf("    %-34s %8.3f %8.3f %8.3f %8.3f %8.3f\n", name, p.p50, p.p90, p.p99, p.max,
              p.mean);
}

// Mean of each segment over the samples whose total is at least `threshold`.
std::vector<double> MeansOfSlowest(const LatencyBreakdown& b, double threshold, size_t* count) {
  std::vector<double> sums(b.names.size(), 0.0);
  *count = 0;
  for (size_t i = 0; i < b.total.size(); ++i) {
    if (b.total[i] < threshold) continue;
    ++*count;
    for (size_t s = 0; s < sums.size(); ++s) sums[s] += b.segments[s][i];
  }
  for (double& sum : sums) sum /= static_cast<double>(std::max<size_t>(*count, 1));
  return sums;
}

}  // namespace

Percentiles Summarize(std::vector<double> values) {
  Percentiles p;
  p.count = values.size();
  if (values.empty()) return p;
  std::sort(values.begin(), values.end());
  const auto rank = [&](double q) {
    const size_t index = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size())));
    return values[std::clamp<size_t>(index, 1, values.size()) - 1];
  };
  p.p50 = rank(0.50);
  p.p90 = rank(0.90);
  p.p99 = rank(0.99);
  p.max = values.back();
  p.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  return p;
}

LatencyBreakdown BreakDown(const std::vector<ShapeSample>& samples) {
  LatencyBreakdown b;
  b.names = {"publish + kernel, to carving", "carving: LCM, last image",
             "carving: its silhouette",      "carving: assembly, queue, carve",
             "voxels -> shape worker",       "shape: silhouettes + estimate",
             "shape -> bench socket"};
  b.segments.resize(b.names.size());
  for (const ShapeSample& sample : samples) {
    const std::optional<Timeline> t = TimelineOf(sample);
    if (!t) {
      ++b.without_stage_times;
      continue;
    }
    const int64_t points[] = {t->trigger,        t->set_complete, t->silhouette_start,
                              t->silhouette_end, t->carving_end,  t->shape_start,
                              t->shape_end,      t->received};
    for (size_t s = 0; s < b.names.size(); ++s)
      b.segments[s].push_back(Ms(points[s], points[s + 1]));
    b.total.push_back(Ms(t->trigger, t->received));
  }
  return b;
}

void PrintBreakdown(const LatencyBreakdown& b) {
  std::printf("    %-34s %8s %8s %8s %8s %8s   (ms)\n", "segment", "p50", "p90", "p99", "max",
              "mean");
  for (size_t s = 0; s < b.names.size(); ++s)
    PrintRow(b.names[s].c_str(), Summarize(b.segments[s]));
  const Percentiles total = Summarize(b.total);
  PrintRow("total: trigger -> shape received", total);
  if (b.without_stage_times > 0) {
    std::printf("    (%lld shapes without the stage times, left out)\n",
                static_cast<long long>(b.without_stage_times));
  }
  if (total.count == 0) return;
  size_t slow = 0;
  const std::vector<double> means = MeansOfSlowest(b, total.p99, &slow);
  std::printf("    slowest 1%% (%zu frame-sets at or above p99), mean ms per segment:\n", slow);
  for (size_t s = 0; s < b.names.size(); ++s) {
    std::printf("      %-32s %8.3f\n", b.names[s].c_str(), means[s]);
  }
}

}  // namespace shapesense::bench
