#pragma once

// The live demo's scoring, in the demo's process: the monitor's LiveScorer
// (losses, per-stage latency, centreline and tip against the virtual rig's
// truth) and, for the same pairs, the whole comparison of libs/evaluation
// (tape markers, coverage); every shape is kept for the replay check.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "clients/tools/monitor/live_scorer.h"
#include "libs/evaluation/shape_error.h"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense {

struct DemoScore {
  LiveScorer::Report live;
  ShapeErrorSummary errors;  // over the valid shapes paired with a truth
};

class DemoScorer {
 public:
  // Pairs as LiveScorer does: the truth nearest in trigger time, within the tolerance.
  explicit DemoScorer(int64_t match_tolerance_us = 12'000);  // as LiveScorer's

  void AddTruth(const shape_t& truth);
  void AddShape(const shape_t& shape, int64_t receive_utime);
  void AddStatus(const service_status_t& status);

  bool StatusSeen(const std::string& service) const { return services_.contains(service); }
  int shapes() const { return static_cast<int>(shapes_.size()); }
  // Every shape received, by trigger sequence.
  const std::map<int64_t, shape_t>& shapes_by_seq() const { return shapes_; }

  // `end_utime`: when the run stopped (see LiveScorer::Finish).
  DemoScore Finish(int64_t end_utime) const;

 private:
  LiveScorer live_;                    // also pairs each shape with its truth (FindTruth)
  std::map<int64_t, shape_t> shapes_;  // by trigger sequence
  std::vector<ShapeError> errors_;
  int invalid_ = 0;
  std::set<std::string> services_;
};

// The virtual rig's truth message as libs/evaluation's ground truth.
GroundTruth GroundTruthFromMessage(const shape_t& truth);

}  // namespace shapesense
