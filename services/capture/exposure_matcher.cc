#include "services/capture/exposure_matcher.h"

#include <limits>

namespace shapesense {
namespace {

// The end of a window whose trigger is still on its way to the camera.
constexpr int64_t kOpen = std::numeric_limits<int64_t>::max() / 2;

// GigE Vision 1.x block ids are 16-bit, skip 0 and wrap: 65535 is followed by 1.
constexpr int64_t kLastShortId = 0xffff;
constexpr int64_t kWrapMargin = 0x100;

bool Wrapped(int64_t last, int64_t id) {
  return last <= kLastShortId && last > kLastShortId - kWrapMargin && id < kWrapMargin;
}

}  // namespace

const char* MatchVerdictName(MatchVerdict verdict) {
  switch (verdict) {
    case MatchVerdict::kMatched:
      return "matched";
    case MatchVerdict::kNoTimestamp:
      return "without exposure timestamp";
    case MatchVerdict::kFutureTimestamp:
      return "stamped after they arrived";
    case MatchVerdict::kRepeatedFrameId:
      return "repeating the last frame id";
    case MatchVerdict::kFrameIdBackwards:
      return "with a frame id going backwards";
    case MatchVerdict::kOutsideWindows:
      return "exposed outside every trigger's window";
    case MatchVerdict::kAmbiguous:
      return "inside two triggers' windows";
    case MatchVerdict::kAnsweredAlready:
      return "for a trigger answered already";
    case MatchVerdict::kLateExposure:
      return "exposed too long after their frame-set's time";
    case MatchVerdict::kCount:
      break;
  }
  return "?";
}

void ExposureMatcher::Sending(int64_t seq, int64_t utime, int64_t sent_utime) {
  Sent({seq, utime, sent_utime, kOpen});
}

void ExposureMatcher::Acknowledged(int64_t seq, int64_t acked_utime) {
  if (!windows_.empty() && windows_.back().trigger.seq == seq) {
    windows_.back().trigger.acked_utime = acked_utime;
  }
}

void ExposureMatcher::Sent(const SentTrigger& trigger) {
  Expire(trigger.sent_utime);
  windows_.push_back({trigger, false});
  // Bounds memory whatever the rate: the oldest window goes first.
  while (windows_.size() > options_.capacity) {
    if (!windows_.front().answered) ++unanswered_;
    windows_.pop_front();
  }
}

MatchVerdict ExposureMatcher::CheckFrameId(int64_t frame_id) const {
  if (frame_id == 0 || last_frame_id_ == 0) return MatchVerdict::kMatched;
  if (frame_id == last_frame_id_) return MatchVerdict::kRepeatedFrameId;
  if (frame_id < last_frame_id_ && !Wrapped(last_frame_id_, frame_id)) {
    return MatchVerdict::kFrameIdBackwards;
  }
  return MatchVerdict::kMatched;
}

MatchResult ExposureMatcher::Count(MatchVerdict verdict, std::optional<SentTrigger> trigger) {
  ++counts_[static_cast<size_t>(verdict)];
  return {verdict, trigger};
}

MatchResult ExposureMatcher::Match(const ExposureStamp& frame) {
  if (frame.exposure_utime <= 0) return Count(MatchVerdict::kNoTimestamp);
  if (frame.exposure_utime > frame.received_utime + options_.clock_tolerance_us) {
    return Count(MatchVerdict::kFutureTimestamp);
  }
  if (const MatchVerdict id = CheckFrameId(frame.frame_id); id != MatchVerdict::kMatched) {
    return Count(id);
  }
  if (frame.frame_id != 0) last_frame_id_ = frame.frame_id;
  const Holders holders = HoldersOf(frame.exposure_utime);
  if (holders.unanswered > 1) return Count(MatchVerdict::kAmbiguous);
  if (holders.unanswered == 0) {
    return Count(holders.answered ? MatchVerdict::kAnsweredAlready : MatchVerdict::kOutsideWindows);
  }
  Window& window = windows_[holders.index];
  window.answered = true;
  if (frame.exposure_utime - window.trigger.utime > options_.max_exposure_delay_us) {
    ++unanswered_;  // its one frame is unusable
    return Count(MatchVerdict::kLateExposure);
  }
  return Count(MatchVerdict::kMatched, window.trigger);
}

// A window already answered cannot hold this frame: a triggered camera
// exposes once per trigger (burst of one), and the frame that answered it
// came earlier.
ExposureMatcher::Holders ExposureMatcher::HoldersOf(int64_t exposure_utime) const {
  Holders holders;
  for (size_t i = 0; i < windows_.size(); ++i) {
    const SentTrigger& t = windows_[i].trigger;
    if (exposure_utime < t.sent_utime || exposure_utime > t.acked_utime + options_.max_latency_us) {
      continue;
    }
    if (windows_[i].answered) {
      holders.answered = true;
    } else {
      ++holders.unanswered;
      holders.index = i;
    }
  }
  return holders;
}

void ExposureMatcher::Expire(int64_t now_utime) {
  while (!windows_.empty()) {
    const Window& oldest = windows_.front();
    const int64_t closes = oldest.trigger.acked_utime + options_.max_latency_us + options_.keep_us;
    if (closes > now_utime) return;
    if (!oldest.answered) ++unanswered_;
    windows_.pop_front();
  }
}

void ExposureMatcher::Reset() {
  for (const Window& window : windows_) {
    if (!window.answered) ++unanswered_;
  }
  windows_.clear();
  last_frame_id_ = 0;
}

int64_t ExposureMatcher::rejected() const {
  int64_t total = 0;
  for (size_t i = 0; i < counts_.size(); ++i) {
    if (static_cast<MatchVerdict>(i) != MatchVerdict::kMatched) total += counts_[i];
  }
  return total;
}

std::string ExposureMatcher::DescribeRejections() const {
  std::string text;
  for (size_t i = 0; i < counts_.size(); ++i) {
    const auto verdict = static_cast<MatchVerdict>(i);
    if (verdict == MatchVerdict::kMatched || counts_[i] == 0) continue;
    text += (text.empty() ? "" : ", ") + std::to_string(counts_[i]) + " frames " +
            MatchVerdictName(verdict);
  }
  return text;
}

}  // namespace shapesense
