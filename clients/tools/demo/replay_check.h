#pragma once

// Does `shapesense replay` on the demo's log give the shapes the live
// pipeline gave? The two are paired by trigger sequence.
#include <cstdint>
#include <map>
#include <string>

#include "shapesense/shape_t.hpp"

namespace shapesense {

struct ReplayCheck {
  bool ran = false;
  std::string error;             // why the replay did not run or failed
  int compared = 0;              // frame-sets with a live and a replayed shape
  int identical = 0;             // of those, the same shape (every coordinate within 1e-9 mm)
  double max_difference_mm = 0;  // largest coordinate difference over the compared ones
  int live_only = 0;             // shapes the replay did not give (sets incomplete in the log)
  int replay_only = 0;           // sets the live services dropped (overload) or never sent
};

// Centreline, tip and markers coordinate by coordinate; a shape valid on one
// side only, or with another number of points, differs by infinity.
double ShapeDifference(const shape_t& a, const shape_t& b);

ReplayCheck CompareReplay(const std::map<int64_t, shape_t>& live,
                          const std::map<int64_t, shape_t>& replayed);

}  // namespace shapesense
