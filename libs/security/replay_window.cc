#include "libs/security/replay_window.h"

namespace shapesense {

ReplayWindow::Verdict ReplayWindow::Check(uint64_t counter) const {
  if (!started_ || counter > highest_) return Verdict::kFresh;
  const uint64_t behind = highest_ - counter;
  if (behind >= kWidth) return Verdict::kTooOld;
  return (seen_ >> behind) & 1u ? Verdict::kReplayed : Verdict::kFresh;
}

ReplayWindow::Verdict ReplayWindow::Accept(uint64_t counter) {
  const Verdict verdict = Check(counter);
  if (verdict != Verdict::kFresh) return verdict;
  if (!started_) {
    started_ = true;
    highest_ = counter;
    seen_ = 1;
  } else if (counter > highest_) {
    const uint64_t ahead = counter - highest_;
    seen_ = ahead >= kWidth ? 1 : (seen_ << ahead) | 1u;
    highest_ = counter;
  } else {
    seen_ |= uint64_t{1} << (highest_ - counter);
  }
  return verdict;
}

}  // namespace shapesense
