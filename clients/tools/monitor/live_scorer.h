#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense {

// Scores a live run: pairs each measured shape with the virtual rig's truth
// of the same frame-set (by trigger time: the two processes count frame-sets
// independently but share the host clock) and gathers accuracy, losses and
// the latency of every stage. Pure bookkeeping: times are passed in.
class LiveScorer {
 public:
  // Shapes and truths whose trigger times differ by at most this are a pair,
  // µs: the virtual rig's truth is at its reference camera's exposure, which
  // the capture service keeps within 10 ms of its frame-set's time
  // (max_exposure_delay_us).
  explicit LiveScorer(int64_t match_tolerance_us = 12'000) : tolerance_us_(match_tolerance_us) {}

  void AddTruth(const shape_t& truth);
  // The truth nearest `trigger_utime` within the match tolerance; nullptr
  // when there is none. Valid until the next AddTruth.
  const shape_t* FindTruth(int64_t trigger_utime) const;
  // `receive_utime`: when the shape reached the monitor.
  void AddShape(const shape_t& shape, int64_t receive_utime);
  void AddStatus(const service_status_t& status);

  struct Percentiles {
    double p50 = 0.0;
    double p99 = 0.0;
    double max = 0.0;
    int count = 0;
  };

  struct Report {
    int truths = 0;  // frame-sets the rig rendered
    int shapes = 0;  // shapes received
    int valid_shapes = 0;
    int matched = 0;                   // valid shapes paired with a truth
    int unmatched_truths = 0;          // rendered, never measured (excluding the run's last 0.5 s)
    double centerline_rms_mean = 0.0;  // mm, over matched frames
    double centerline_rms_max = 0.0;
    double tip_error_mean = 0.0;
    double tip_error_max = 0.0;
    std::map<std::string, Percentiles> stage_ms;  // per stage, from the shapes' stage times
    // trigger → shape received (on a rig of several hosts: the shape's age at publish)
    Percentiles trigger_to_shape_ms;
    std::map<std::string, service_status_t> last_status;  // per service
  };

  // `end_utime`: when the run stopped; truths in the last `grace_us` are not
  // counted as lost (their shapes may still have been in flight).
  Report Finish(int64_t end_utime, int64_t grace_us = 500'000) const;

 private:
  struct Pair {
    double centerline_rms = 0.0;
    double tip_error = 0.0;
  };

  int64_t tolerance_us_;
  std::map<int64_t, shape_t> truths_;  // by trigger time
  std::vector<Pair> pairs_;
  std::vector<int64_t> matched_truth_times_;
  int shapes_ = 0;
  int valid_shapes_ = 0;
  std::map<std::string, std::vector<double>> stage_ms_;
  std::vector<double> trigger_to_shape_ms_;
  std::map<std::string, service_status_t> last_status_;
};

}  // namespace shapesense
