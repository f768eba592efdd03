#pragma once

// Which software trigger a camera frame answers. Header-only: the capture
// library builds the Aravis backend from aravis_camera.cc alone.
//
// A camera makes one frame per trigger, in order, but frames get lost on the
// wire (never delivered), a camera can miss a trigger (busy, or two triggers
// merged), and at high rates a frame arrives after the next trigger was sent.
// Counting frames alone would then shift every later frame onto the wrong
// frame-set, so frames are matched by time:
//
//   * a frame can only answer a trigger sent before the frame was received;
//   * D = device timestamp - trigger send time (device clock minus host clock)
//     is the same for every frame up to the trigger latency's jitter: the
//     camera's clock offset plus the time from trigger to exposure. An older
//     trigger gives a D larger by whole trigger periods, a newer one smaller.
//
// The reference D is a low quantile of the D of recent matches (robust to one
// outlier, following clock drift). A frame takes the newest eligible trigger
// whose D is not below the reference by more than a tolerance (30% of the
// trigger period, 2-20 ms); older pending triggers are stale (their frames
// were lost or never made) and are dropped. The first frame after a reset
// takes the oldest eligible trigger; a frame whose D is below every
// reference (the reference came from a late first frame) takes the newest
// eligible one. Without device timestamps, frames are counted, skipping the
// triggers of frames whose ids are missing.

#include <algorithm>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace shapesense {

struct PendingTrigger {
  int64_t seq = 0;
  int64_t utime = 0;       // the frame-set's trigger time (as given to Trigger())
  int64_t sent_utime = 0;  // when the trigger left this host
};

struct FrameTiming {
  int64_t frame_id = 0;        // camera counter; 0 when unknown
  int64_t device_ns = 0;       // device timestamp; 0 when unknown
  int64_t received_utime = 0;  // host clock, when the frame began to arrive
};

class TriggerMatcher {
 public:
  // At most `capacity` triggers wait for frames; older ones are dropped as stale.
  explicit TriggerMatcher(size_t capacity = 64) : capacity_(capacity) {}

  void Sent(const PendingTrigger& trigger) {
    if (!pending_.empty()) RecordInterval(trigger.sent_utime - pending_.back().sent_utime);
    pending_.push_back(trigger);
    while (pending_.size() > capacity_) DropOldest();
  }

  // The trigger `frame` answers, or nullopt when no pending trigger was sent
  // before it arrived. Every older pending trigger is dropped as stale.
  std::optional<PendingTrigger> Match(const FrameTiming& frame) {
    const size_t eligible = EligibleCount(frame.received_utime);
    if (eligible == 0) return std::nullopt;
    const size_t pick = Pick(frame, eligible);
    for (size_t i = 0; i < pick; ++i) DropOldest();
    const PendingTrigger match = pending_.front();
    pending_.pop_front();
    if (frame.device_ns != 0) RecordOffset(frame.device_ns / 1000 - match.sent_utime);
    if (frame.frame_id != 0) last_frame_id_ = frame.frame_id;
    return match;
  }

  // Forgets every trigger and what was learnt (after the camera reopens).
  void Reset() {
    pending_.clear();
    offsets_.clear();
    intervals_.clear();
    last_frame_id_ = 0;
  }

  size_t pending() const { return pending_.size(); }
  int64_t stale() const { return stale_; }

 private:
  static constexpr size_t kHistory = 16;

  size_t EligibleCount(int64_t received_utime) const {
    size_t count = 0;
    while (count < pending_.size() && pending_[count].sent_utime <= received_utime) ++count;
    return count;
  }

  size_t Pick(const FrameTiming& frame, size_t eligible) const {
    if (frame.device_ns == 0) return std::min(MissingFrames(frame.frame_id), eligible - 1);
    if (offsets_.empty()) return 0;
    const int64_t floor = ReferenceOffset() - Tolerance();
    for (size_t i = eligible; i-- > 0;) {
      if (frame.device_ns / 1000 - pending_[i].sent_utime >= floor) return i;
    }
    return eligible - 1;
  }

  // Frames missing between the last frame and this one, from the ids
  // (GigE Vision ids are 16-bit, skip 0, and wrap).
  size_t MissingFrames(int64_t frame_id) const {
    if (frame_id == 0 || last_frame_id_ == 0) return 0;
    int64_t gap = frame_id - last_frame_id_;
    if (gap <= 0 && last_frame_id_ <= 0xffff) gap += 0xffff;
    return gap >= 1 && gap <= static_cast<int64_t>(capacity_) ? static_cast<size_t>(gap - 1) : 0;
  }

  // Second smallest recent offset: one early outlier does not pull it down.
  int64_t ReferenceOffset() const {
    std::vector<int64_t> sorted(offsets_.begin(), offsets_.end());
    std::sort(sorted.begin(), sorted.end());
    return sorted[std::min<size_t>(1, sorted.size() - 1)];
  }

  int64_t Tolerance() const {
    int64_t period = 33'000;
    if (!intervals_.empty()) {
      std::vector<int64_t> sorted(intervals_.begin(), intervals_.end());
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      period = sorted[sorted.size() / 2];
    }
    return std::clamp<int64_t>(period * 3 / 10, 2'000, 20'000);
  }

  void RecordOffset(int64_t offset) {
    offsets_.push_back(offset);
    if (offsets_.size() > kHistory) offsets_.pop_front();
  }

  void RecordInterval(int64_t interval) {
    if (interval <= 0) return;
    intervals_.push_back(interval);
    if (intervals_.size() > kHistory) intervals_.pop_front();
  }

  void DropOldest() {
    pending_.pop_front();
    ++stale_;
  }

  size_t capacity_;
  std::deque<PendingTrigger> pending_;
  std::deque<int64_t> offsets_;    // device µs - trigger send µs of recent matches
  std::deque<int64_t> intervals_;  // between consecutive triggers, µs
  int64_t last_frame_id_ = 0;
  int64_t stale_ = 0;
};

}  // namespace shapesense
