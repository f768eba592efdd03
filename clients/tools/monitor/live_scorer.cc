#include "clients/tools/monitor/live_scorer.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "libs/geometry/polyline.h"

namespace shapesense {
namespace {

Polyline ToPolyline(const std::vector<std::vector<double>>& points) {
  Polyline out;
  out.reserve(points.size());
  for (const auto& p : points) {
    if (p.size() == 3) out.emplace_back(p[0], p[1], p[2]);
  }
  return out;
}

LiveScorer::Percentiles Summarize(std::vector<double> values) {
  LiveScorer::Percentiles out;
  out.count = static_cast<int>(values.size());
  if (values.empty()) return out;
  std::sort(values.begin(), values.end());
  auto at = [&](double q) {
    const size_t index = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size()))) - 1;
    return values[std::min(index, values.size() - 1)];
  };
  out.p50 = at(0.50);
  out.p99 = at(0.99);
  out.max = values.back();
  return out;
}

// The trigger time is the camera host's clock: on another host, the
// shape's age (summed hop by hop on each host's own clock) stands in for
// receive - trigger, short of the last hop's transit.
int64_t TriggerToShapeUs(const shape_t& shape, int64_t receive_utime) {
  if (shape.header.data_age_us > 0) return shape.header.data_age_us;
  return receive_utime - shape.trigger_utime;
}

}  // namespace

void LiveScorer::AddTruth(const shape_t& truth) { truths_[truth.trigger_utime] = truth; }

const shape_t* LiveScorer::FindTruth(int64_t trigger_utime) const {
  const shape_t* best = nullptr;
  int64_t best_gap = tolerance_us_ + 1;
  auto consider = [&](std::map<int64_t, shape_t>::const_iterator it) {
    if (it == truths_.end()) return;
    const int64_t gap = std::llabs(it->first - trigger_utime);
    if (gap < best_gap) {
      best_gap = gap;
      best = &it->second;
    }
  };
  const auto after = truths_.lower_bound(trigger_utime);
  consider(after);
  if (after != truths_.begin()) consider(std::prev(after));
  return best;
}

void LiveScorer::AddShape(const shape_t& shape, int64_t receive_utime) {
  ++shapes_;
  for (const stage_time_t& stage : shape.stage_times) {
    stage_ms_[stage.stage].push_back(static_cast<double>(stage.duration_us) * 1e-3);
  }
  trigger_to_shape_ms_.push_back(static_cast<double>(TriggerToShapeUs(shape, receive_utime)) *
                                 1e-3);
  if (!shape.valid) return;
  ++valid_shapes_;
  const shape_t* truth = FindTruth(shape.trigger_utime);
  if (truth == nullptr) return;
  const Polyline measured = ToPolyline(shape.centerline);
  const Polyline expected = ToPolyline(truth->centerline);
  if (measured.empty() || expected.size() < 2) return;
  const Vec3 tip(shape.tip[0], shape.tip[1], shape.tip[2]);
  const Vec3 true_tip(truth->tip[0], truth->tip[1], truth->tip[2]);
  pairs_.push_back({RmsDistanceToPolyline(measured, expected), (tip - true_tip).norm()});
  matched_truth_times_.push_back(truth->trigger_utime);
}

void LiveScorer::AddStatus(const service_status_t& status) {
  last_status_[status.service] = status;
}

LiveScorer::Report LiveScorer::Finish(int64_t end_utime, int64_t grace_us) const {
  Report report;
  report.truths = static_cast<int>(truths_.size());
  report.shapes = shapes_;
  report.valid_shapes = valid_shapes_;
  report.matched = static_cast<int>(pairs_.size());
  const std::set<int64_t> matched(matched_truth_times_.begin(), matched_truth_times_.end());
  for (const auto& [time, truth] : truths_) {
    if (!matched.contains(time) && time < end_utime - grace_us) ++report.unmatched_truths;
  }
  for (const Pair& pair : pairs_) {
    report.centerline_rms_mean += pair.centerline_rms;
    report.centerline_rms_max = std::max(report.centerline_rms_max, pair.centerline_rms);
    report.tip_error_mean += pair.tip_error;
    report.tip_error_max = std::max(report.tip_error_max, pair.tip_error);
  }
  if (!pairs_.empty()) {
    report.centerline_rms_mean /= static_cast<double>(pairs_.size());
    report.tip_error_mean /= static_cast<double>(pairs_.size());
  }
  for (const auto& [stage, values] : stage_ms_) report.stage_ms[stage] = Summarize(values);
  report.trigger_to_shape_ms = Summarize(trigger_to_shape_ms_);
  report.last_status = last_status_;
  return report;
}

}  // namespace shapesense
