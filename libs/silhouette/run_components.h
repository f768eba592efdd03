#pragma once

#include <cstdint>
#include <vector>

#include "libs/silhouette/bit_mask.h"

namespace shapesense {

// Pixels [x0, x1) of row y.
struct RowRun {
  int y = 0;
  int x0 = 0;
  int x1 = 0;
};

// The foreground of a binary image as runs in raster order; the runs of row y
// are runs[row_begin[y]] … runs[row_begin[y + 1] - 1].
struct RunImage {
  std::vector<RowRun> runs;
  std::vector<int> row_begin;
};

void ExtractRuns(const BitMask& mask, RunImage* out);

// Union-find state reused between calls.
struct ComponentScratch {
  std::vector<int> parent;
  std::vector<int64_t> area;
};

// The runs of the 8-connected components that are the manipulator: always the
// largest component (on a tie, the one whose first pixel comes first in raster
// order), and every other of at least `min_area` pixels. Union-find over the
// runs, so the cost follows the foreground, not the image. `kept` is in raster
// order.
void KeepManipulatorComponents(const RunImage& runs, int64_t min_area, ComponentScratch* scratch,
                               std::vector<RowRun>* kept);

}  // namespace shapesense
