#include "services/rig_sim/frame_set_clock.h"

#include <algorithm>

namespace shapesense {
namespace {

constexpr size_t kRecentSets = 64;
// The trigger period is the median interval between this many recent sets.
constexpr size_t kPeriodSets = 16;
// Before the period is known, a trigger this close to a set's first is its.
constexpr int64_t kUnknownPeriodTolerance = 10'000;
// A camera's first image with no acquisition start known looks back this far.
constexpr int64_t kUnknownSessionUs = 150'000;

}  // namespace

FrameSetClock::Slot FrameSetClock::Assign(int camera, int64_t now_utime,
                                          int64_t session_start_utime) {
  int64_t& next = next_[static_cast<size_t>(camera)];
  if (session_start_utime >= 0 || next < 0) {
    return FirstOfSession(
        camera, now_utime,
        session_start_utime >= 0 ? session_start_utime : now_utime - kUnknownSessionUs);
  }
  const int64_t seq = std::max(next, seq_);
  next = seq + 1;
  return seq > seq_ ? Open(now_utime) : Recent(seq);
}

FrameSetClock::Slot FrameSetClock::AssignByTrigger(int camera, int64_t trigger_utime) {
  const int64_t period = Period();
  const int64_t tolerance =
      period > 0 ? std::clamp<int64_t>(period * 3 / 10, 2'000, 20'000) : kUnknownPeriodTolerance;
  // The newest set whose first trigger came before this one (give or take
  // the tolerance), unless the camera served it already or this trigger is
  // a period later: then it is the next set's.
  const auto newest = std::find_if(recent_.rbegin(), recent_.rend(), [&](const Opened& set) {
    return set.first_utime <= trigger_utime + tolerance;
  });
  int64_t& next = next_[static_cast<size_t>(camera)];
  const bool joins = newest != recent_.rend() && newest->seq >= next &&
                     (period > 0 ? trigger_utime - newest->first_utime < period - tolerance
                                 : trigger_utime - newest->first_utime <= tolerance);
  const Slot slot = joins ? Recent(newest->seq) : Open(trigger_utime);
  next = slot.seq + 1;
  return slot;
}

int64_t FrameSetClock::Period() const {
  if (recent_.size() < 2) return 0;
  std::vector<int64_t> gaps;
  for (size_t i = recent_.size() > kPeriodSets ? recent_.size() - kPeriodSets : 1;
       i < recent_.size(); ++i) {
    gaps.push_back(recent_[i].first_utime - recent_[i - 1].first_utime);
  }
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                   gaps.end());
  return gaps[gaps.size() / 2];
}

FrameSetClock::Slot FrameSetClock::FirstOfSession(int camera, int64_t now_utime,
                                                  int64_t session_start_utime) {
  const auto oldest = std::find_if(recent_.begin(), recent_.end(), [&](const Opened& set) {
    return set.first_utime >= session_start_utime;
  });
  const Slot slot = oldest != recent_.end() ? Recent(oldest->seq) : Open(now_utime);
  // The image answered every trigger sent so far.
  next_[static_cast<size_t>(camera)] = seq_ + 1;
  return slot;
}

FrameSetClock::Slot FrameSetClock::Open(int64_t now_utime) {
  ++seq_;
  recent_.push_back({seq_, now_utime});
  if (recent_.size() > kRecentSets) recent_.pop_front();
  return {seq_, now_utime, true};
}

FrameSetClock::Slot FrameSetClock::Recent(int64_t seq) const {
  for (const Opened& set : recent_) {
    if (set.seq == seq) return {seq, set.first_utime, false};
  }
  return {seq, recent_.empty() ? 0 : recent_.front().first_utime, false};  // older than kept
}

}  // namespace shapesense
