#include "runtime/lcm/frame_set_assembler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

namespace shapesense {
namespace {

// Late images are recognised among this many recently retired sets per
// pending slot: enough to outlast any reordering LCM can produce.
constexpr size_t kRetiredPerPending = 4;

int64_t ImageTime(const image_t& image) {
  return image.trigger_utime > 0 ? image.trigger_utime : image.host_utime;
}

int64_t Microseconds(double ms) { return static_cast<int64_t>(std::llround(ms * 1e3)); }

}  // namespace

std::string FrameSetAssemblyOptions::Validate() const {
  if (!(time_tolerance_ms >= 0 && time_tolerance_ms <= 1000)) {
    return "time_tolerance_ms: expected 0-1000, got " + std::to_string(time_tolerance_ms);
  }
  if (!(timeout_ms >= 1 && timeout_ms <= 60000)) {
    return "timeout_ms: expected 1-60000, got " + std::to_string(timeout_ms);
  }
  if (max_pending < 1 || max_pending > 1000) {
    return "max_pending: expected 1-1000, got " + std::to_string(max_pending);
  }
  if (!(max_exposure_spread_ms >= 0.01 && max_exposure_spread_ms <= 1000)) {
    return "max_exposure_spread_ms: expected 0.01-1000, got " +
           std::to_string(max_exposure_spread_ms);
  }
  return {};
}

const char* AssemblyOutcomeName(AssemblyOutcome outcome) {
  switch (outcome) {
    case AssemblyOutcome::kPending:
      return "pending";
    case AssemblyOutcome::kCompleted:
      return "completed";
    case AssemblyOutcome::kDuplicate:
      return "duplicate image";
    case AssemblyOutcome::kConflicting:
      return "conflicting images";
    case AssemblyOutcome::kSpread:
      return "exposures too far apart";
    case AssemblyOutcome::kUnknownCamera:
      return "unknown camera";
    case AssemblyOutcome::kLate:
      return "late image";
  }
  return "?";
}

bool IsRejection(AssemblyOutcome outcome) {
  return outcome == AssemblyOutcome::kDuplicate || outcome == AssemblyOutcome::kConflicting ||
         outcome == AssemblyOutcome::kUnknownCamera || outcome == AssemblyOutcome::kLate;
}

FrameSetAssembler::FrameSetAssembler(std::vector<std::string> cameras,
                                     const FrameSetAssemblyOptions& options)
    : cameras_(std::move(cameras)),
      options_(options),
      tolerance_us_(Microseconds(options.time_tolerance_ms)),
      timeout_us_(Microseconds(options.timeout_ms)),
      max_spread_us_(Microseconds(options.max_exposure_spread_ms)) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("frame-set assembly: " + error);
  }
  const std::set<std::string> unique(cameras_.begin(), cameras_.end());
  if (cameras_.empty() || unique.size() != cameras_.size() || unique.contains("")) {
    throw std::invalid_argument("frame-set assembly: expected distinct, named cameras");
  }
}

int FrameSetAssembler::CameraIndex(const std::string& name) const {
  const auto it = std::find(cameras_.begin(), cameras_.end(), name);
  return it == cameras_.end() ? -1 : static_cast<int>(it - cameras_.begin());
}

FrameSetAssembler::Pending* FrameSetAssembler::FindSet(const image_t& image, int64_t image_time) {
  if (image.trigger_seq >= 0) {
    for (Pending& pending : pending_) {
      if (pending.set.trigger_seq == image.trigger_seq) return &pending;
    }
    return nullptr;
  }
  // Free-running: the set whose first image is nearest in time, within the tolerance.
  Pending* nearest = nullptr;
  int64_t best = tolerance_us_;
  for (Pending& pending : pending_) {
    if (pending.set.trigger_seq >= 0) continue;
    const int64_t gap = std::abs(image_time - pending.reference_utime);
    if (gap <= best) {
      best = gap;
      nearest = &pending;
    }
  }
  return nearest;
}

bool FrameSetAssembler::IsRetired(const image_t& image, int64_t image_time) const {
  return std::any_of(retired_.begin(), retired_.end(), [&](const FrameSetKey& key) {
    if (image.trigger_seq >= 0) return key.trigger_seq == image.trigger_seq;
    return key.trigger_seq < 0 && std::abs(key.trigger_utime - image_time) <= tolerance_us_;
  });
}

FrameSetAssembler::Pending& FrameSetAssembler::StartSet(const image_t& image, int64_t image_time,
                                                        int64_t now_utime) {
  if (pending_.size() >= static_cast<size_t>(options_.max_pending)) {
    Drop(pending_.front(), "too many incomplete sets");
    pending_.pop_front();
    ++counters_.evicted;
  }
  Pending& pending = pending_.emplace_back();
  pending.reference_utime = image_time;
  pending.given_trigger_utime = image.trigger_utime;
  pending.set.trigger_seq = image.trigger_seq >= 0 ? image.trigger_seq : -1;
  pending.set.trigger_utime = image_time;
  pending.set.images.resize(cameras_.size());
  pending.set.receive_utime.assign(cameras_.size(), 0);
  pending.set.first_receive_utime = now_utime;
  return pending;
}

void FrameSetAssembler::Retire(const Pending& pending) {
  retired_.push_back({pending.set.trigger_seq, pending.reference_utime});
  while (retired_.size() > kRetiredPerPending * static_cast<size_t>(options_.max_pending)) {
    retired_.pop_front();
  }
}

void FrameSetAssembler::Drop(const Pending& pending, const char* why) {
  Retire(pending);
  std::string missing;
  for (size_t i = 0; i < cameras_.size(); ++i) {
    if (pending.set.images[i].camera.empty())
      missing += (missing.empty() ? "" : ", ") + cameras_[i];
  }
  const FrameSet& set = pending.set;
  last_drop_ =
      (set.trigger_seq >= 0 ? "frame-set " + std::to_string(set.trigger_seq)
                            : "frame-set at " + std::to_string(set.trigger_utime) + " us") +
      " dropped (" + why + "): no image from " + missing;
}

int FrameSetAssembler::Expire(int64_t now_utime) {
  int expired = 0;
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (now_utime - it->set.first_receive_utime <= timeout_us_) {
      ++it;
      continue;
    }
    Drop(*it, "timed out");
    it = pending_.erase(it);
    ++expired;
  }
  counters_.timed_out += expired;
  return expired;
}

bool FrameSetAssembler::Conflicts(const Pending& pending, const image_t& image, size_t slot) const {
  if (pending.set.trigger_seq < 0) return false;  // matched by time: nothing to contradict
  const image_t& held = pending.set.images[slot];
  if (!held.camera.empty() &&
      (held.frame_id != image.frame_id || held.device_timestamp_ns != image.device_timestamp_ns)) {
    return true;
  }
  return pending.received > 0 && image.trigger_utime != pending.given_trigger_utime;
}

int64_t FrameSetAssembler::ExposureSpread(const FrameSet& set) {
  int64_t earliest = std::numeric_limits<int64_t>::max();
  int64_t latest = std::numeric_limits<int64_t>::min();
  for (const image_t& image : set.images) {
    if (image.device_timestamp_ns <= 0) return 0;
    earliest = std::min(earliest, image.device_timestamp_ns);
    latest = std::max(latest, image.device_timestamp_ns);
  }
  return (latest - earliest) / 1000;
}

AssemblyResult FrameSetAssembler::DropConflicting(Pending* pending) {
  Drop(*pending, "its images disagree on their trigger");
  const auto it = std::find_if(pending_.begin(), pending_.end(),
                               [&](const Pending& p) { return &p == pending; });
  pending_.erase(it);
  ++counters_.conflicting;
  return {AssemblyOutcome::kConflicting, std::nullopt};
}

AssemblyResult FrameSetAssembler::Add(image_t image, int64_t now_utime) {
  Expire(now_utime);
  const int camera = CameraIndex(image.camera);
  if (camera < 0) {
    ++counters_.unknown_camera;
    return {AssemblyOutcome::kUnknownCamera, std::nullopt};
  }
  const int64_t image_time = ImageTime(image);
  Pending* pending = FindSet(image, image_time);
  if (pending == nullptr && IsRetired(image, image_time)) {
    ++counters_.late;
    return {AssemblyOutcome::kLate, std::nullopt};
  }
  if (pending == nullptr) pending = &StartSet(image, image_time, now_utime);
  const size_t slot = static_cast<size_t>(camera);
  if (Conflicts(*pending, image, slot)) return DropConflicting(pending);
  if (!pending->set.images[slot].camera.empty()) {
    ++counters_.duplicates;
    return {AssemblyOutcome::kDuplicate, std::nullopt};
  }
  pending->set.trigger_utime = std::min(pending->set.trigger_utime, image_time);
  pending->set.images[slot] = std::move(image);
  pending->set.receive_utime[slot] = now_utime;
  if (++pending->received < static_cast<int>(cameras_.size()))
    return {AssemblyOutcome::kPending, std::nullopt};

  pending->set.complete_utime = now_utime;
  Retire(*pending);
  const auto it = std::find_if(pending_.begin(), pending_.end(),
                               [&](const Pending& p) { return &p == pending; });
  const int64_t spread = it->set.trigger_seq >= 0 ? ExposureSpread(it->set) : 0;
  if (spread > max_spread_us_) {
    last_drop_ = "frame-set " + std::to_string(it->set.trigger_seq) +
                 " dropped: its exposures lie " + std::to_string(spread) + " us apart";
    pending_.erase(it);
    ++counters_.spread;
    return {AssemblyOutcome::kSpread, std::nullopt};
  }
  AssemblyResult result{AssemblyOutcome::kCompleted, std::move(it->set)};
  pending_.erase(it);
  ++counters_.completed;
  return result;
}

int64_t MeasuredUtime(const FrameSet& set) {
  int64_t earliest = std::numeric_limits<int64_t>::max();
  for (size_t k = 0; k < set.images.size() && k < set.receive_utime.size(); ++k) {
    earliest = std::min(earliest, set.receive_utime[k] - set.images[k].header.data_age_us);
  }
  return earliest == std::numeric_limits<int64_t>::max() ? set.complete_utime : earliest;
}

}  // namespace shapesense
