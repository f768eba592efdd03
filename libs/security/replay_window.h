#pragma once

// Freshness of a sender's messages by its counter, never by a clock: a
// counter above every one seen is fresh (and moves the window up), one
// within the last kWidth that was not seen yet is fresh too (UDP reorders),
// one seen already is a replay, one below the window is too old to tell.
// Clock offsets between hosts cannot break it.
#include <cstdint>

namespace shapesense {

class ReplayWindow {
 public:
  static constexpr uint64_t kWidth = 64;
  enum class Verdict { kFresh, kReplayed, kTooOld };

  // What Accept(counter) would say, changing nothing.
  Verdict Check(uint64_t counter) const;
  // Checks and, when fresh, records it. Call only once the message is
  // known authentic, so that forgeries cannot move the window.
  Verdict Accept(uint64_t counter);

 private:
  bool started_ = false;
  uint64_t highest_ = 0;
  uint64_t seen_ = 0;  // bit i: highest_ - i was seen
};

}  // namespace shapesense
