#include "services/rig_sim/frame_set_clock.h"

#include <algorithm>

namespace shapesense {
namespace {

constexpr size_t kRecentSets = 64;
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
