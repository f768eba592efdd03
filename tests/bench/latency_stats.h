#pragma once

// Latency figures of the live pipeline bench: percentiles, and the time from
// trigger to shape cut into consecutive segments by the stage times a shape
// carries (runtime/lcm/pipeline_stages.h), so that the segments of one
// frame-set add up to its total.
#include <cstdint>
#include <string>
#include <vector>

#include "shapesense/stage_time_t.hpp"

namespace shapesense::bench {

// One shape as the bench received it.
struct ShapeSample {
  int64_t trigger_seq = -1;
  int64_t trigger_utime = 0;  // stamped by the bench when it published the set
  int64_t receive_utime = 0;  // the shape's arrival (LCM's kernel receive time)
  bool valid = false;         // the estimate succeeded
  std::vector<stage_time_t> stages;
};

struct Percentiles {
  double p50 = 0.0, p90 = 0.0, p99 = 0.0, max = 0.0, mean = 0.0;
  size_t count = 0;
};

// Nearest-rank percentiles; all zero for no values.
Percentiles Summarize(std::vector<double> values);

// Segments of trigger → shape received, ms, one value per sample in each.
struct LatencyBreakdown {
  std::vector<std::string> names;             // in pipeline order
  std::vector<std::vector<double>> segments;  // [segment][sample]
  std::vector<double> total;                  // [sample]
  int64_t without_stage_times = 0;            // samples left out (a stage missing)
};

// Cuts every sample at the ends and starts of its "transport", "silhouette",
// "carving" and "shape" stages (all stamped on this host's clock).
LatencyBreakdown BreakDown(const std::vector<ShapeSample>& samples);

// Prints p50 / p90 / p99 / max / mean of each segment and of the total, then
// where the time went in the slowest 1% of frame-sets (mean of each segment
// over the samples at or above the total's p99).
void PrintBreakdown(const LatencyBreakdown& breakdown);

}  // namespace shapesense::bench
