#include "clients/tools/demo/replay_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace shapesense {
namespace {

constexpr double kSame = 1e-9;  // mm

double PointsDifference(const std::vector<std::vector<double>>& a,
                        const std::vector<std::vector<double>>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double largest = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].size() != b[i].size()) return std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < a[i].size(); ++k)
      largest = std::max(largest, std::abs(a[i][k] - b[i][k]));
  }
  return largest;
}

}  // namespace

double ShapeDifference(const shape_t& a, const shape_t& b) {
  if (a.valid != b.valid) return std::numeric_limits<double>::infinity();
  double largest = std::max(PointsDifference(a.centerline, b.centerline),
                            PointsDifference(a.markers, b.markers));
  for (int k = 0; k < 3; ++k) largest = std::max(largest, std::abs(a.tip[k] - b.tip[k]));
  return largest;
}

ReplayCheck CompareReplay(const std::map<int64_t, shape_t>& live,
                          const std::map<int64_t, shape_t>& replayed) {
  ReplayCheck check;
  check.ran = true;
  for (const auto& [seq, shape] : live) {
    const auto other = replayed.find(seq);
    if (other == replayed.end()) {
      ++check.live_only;
      continue;
    }
    const double difference = ShapeDifference(shape, other->second);
    ++check.compared;
    if (difference <= kSame) ++check.identical;
    check.max_difference_mm = std::max(check.max_difference_mm, difference);
  }
  for (const auto& [seq, shape] : replayed) check.replay_only += live.contains(seq) ? 0 : 1;
  return check;
}

}  // namespace shapesense
