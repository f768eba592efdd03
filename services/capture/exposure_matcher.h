#pragma once

// Which trigger a camera frame answers, proven from the frame's exposure
// timestamp, never guessed from arrival order.
//
// The camera's timestamps are on the host's clock: a GigE Vision camera
// synchronised by PTP (IEEE 1588, with phc2sys tying the host's clock to the
// NIC's), or the virtual rig's cameras, which share the host's clock. Each
// software trigger is sent between two host times (just before the GVCP
// write and when the camera acknowledged it), so the camera received it
// inside that interval and began the exposure it causes at most the
// camera's trigger latency later. Trigger k's window is therefore
//
//     [sent_k, acked_k + max_latency]
//
// and an exposure can only have been caused by a trigger whose window holds
// its timestamp. A triggered camera exposes once per trigger, so a window
// whose trigger has its frame holds no other. A frame is matched when
// exactly one unanswered window holds it; it is dropped, with its reason
// counted, when none does (the camera answered outside its latency, or its
// clock is not synchronised), when two do (triggers too close for this
// latency), when only answered ones do (a second exposure for one trigger),
// or when it was exposed more than `max_exposure_delay_us` after its
// frame-set's time (its trigger reached a busy camera late). Frames may
// arrive in any order and up to `keep_us` late: the windows are kept that
// long. A trigger that got no usable frame is counted unanswered (a missed
// trigger, a lost frame, or one exposed too late).
//
// A window is opened before its trigger leaves (Sending) and closed when the
// camera acknowledges it (Acknowledged): a frame that arrives before the
// sender has noted the acknowledgement still finds its window. Triggers to
// one camera go out one at a time, so only the newest window can be open.
//
// Sanity checks on the camera's own facts drop a frame whose id repeats the
// last one's (a duplicate) or goes backwards (other than the GigE Vision
// 16-bit wrap), and one stamped after it was received (a timestamp in the
// future: a clock that is not the host's).

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>

namespace shapesense {

struct SentTrigger {
  int64_t seq = 0;          // the frame-set's trigger sequence
  int64_t utime = 0;        // the frame-set's trigger time, µs since epoch
  int64_t sent_utime = 0;   // host clock, just before the trigger left
  int64_t acked_utime = 0;  // host clock, when the camera acknowledged it
};

struct ExposureStamp {
  int64_t frame_id = 0;        // the camera's frame (block) id; 0 unknown
  int64_t exposure_utime = 0;  // exposure start on the host's clock; 0 unknown
  int64_t received_utime = 0;  // host clock, when the frame began to arrive
};

enum class MatchVerdict {
  kMatched,
  kNoTimestamp,       // the frame has no exposure timestamp: nothing proves its trigger
  kFutureTimestamp,   // stamped after it was received: the camera's clock is not the host's
  kRepeatedFrameId,   // the same frame id as the last frame: a duplicate
  kFrameIdBackwards,  // an older frame id than the last frame's
  kOutsideWindows,    // no trigger's window holds the exposure
  kAmbiguous,         // two triggers' windows hold it
  kAnsweredAlready,   // the one trigger whose window holds it has its frame
  kLateExposure,      // exposed too long after its frame-set's time (its trigger reached a
                      // busy camera late): the image shows a later moment
  kCount,
};
const char* MatchVerdictName(MatchVerdict verdict);

struct MatchResult {
  MatchVerdict verdict = MatchVerdict::kOutsideWindows;
  std::optional<SentTrigger> trigger;  // with kMatched
};

struct ExposureMatcherOptions {
  // Longest time from a camera receiving a trigger to its exposure starting, µs.
  int64_t max_latency_us = 4'000;
  // How long after its window a trigger still takes a late-arriving frame, µs.
  int64_t keep_us = 1'000'000;
  // How far past its receipt an exposure stamp may lie before it is called
  // in the future (PTP's residual error), µs.
  int64_t clock_tolerance_us = 500;
  // A frame exposed later than this after its frame-set's time (the
  // trigger's `utime`) shows another moment than the set's: dropped, µs.
  int64_t max_exposure_delay_us = 10'000;
  // Triggers remembered at most (the oldest are forgotten first).
  size_t capacity = 1024;
};

class ExposureMatcher {
 public:
  explicit ExposureMatcher(ExposureMatcherOptions options = {}) : options_(options) {}

  // Opens trigger `seq`'s window as it leaves at `sent_utime` (for a frame-set
  // triggered at `utime`); its end stays open until Acknowledged().
  void Sending(int64_t seq, int64_t utime, int64_t sent_utime);
  // Closes the newest window: the camera acknowledged trigger `seq`.
  void Acknowledged(int64_t seq, int64_t acked_utime);
  // Sending() and Acknowledged() at once.
  void Sent(const SentTrigger& trigger);
  MatchResult Match(const ExposureStamp& frame);
  // Counts as unanswered the triggers whose window and keep time passed by
  // `now_utime` with no frame, and forgets them.
  void Expire(int64_t now_utime);
  // Forgets every trigger and the last frame id (the camera reopened: its
  // ids start again); the counters stay.
  void Reset();

  int64_t count(MatchVerdict verdict) const { return counts_[static_cast<size_t>(verdict)]; }
  int64_t unanswered() const { return unanswered_; }
  // Frames dropped for any reason.
  int64_t rejected() const;
  // "3 frames exposed outside every trigger's window, 1 frames inside two
  // triggers' windows", or "" when none.
  std::string DescribeRejections() const;

 private:
  struct Window {
    SentTrigger trigger;
    bool answered = false;
  };
  // The windows holding an exposure.
  struct Holders {
    size_t unanswered = 0;  // how many unanswered ones
    size_t index = 0;       // the last of them
    bool answered = false;  // whether an answered one does too
  };
  MatchVerdict CheckFrameId(int64_t frame_id) const;
  Holders HoldersOf(int64_t exposure_utime) const;
  MatchResult Count(MatchVerdict verdict, std::optional<SentTrigger> trigger = std::nullopt);

  ExposureMatcherOptions options_;
  std::deque<Window> windows_;  // in the order sent
  int64_t last_frame_id_ = 0;
  std::array<int64_t, static_cast<size_t>(MatchVerdict::kCount)> counts_{};
  int64_t unanswered_ = 0;
};

}  // namespace shapesense
