#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

namespace shapesense {

// A software trigger waiting for its frame.
struct QueuedTrigger {
  int64_t seq = 0;
  int64_t utime = 0;  // µs since epoch
};

// Software triggers from the trigger thread to a camera's grab thread.
// Push never blocks; when a camera falls behind by more than `capacity`
// triggers the oldest is dropped (its frame-set will miss this camera, which
// the carving service counts) rather than delaying every later frame.
class TriggerQueue {
 public:
  explicit TriggerQueue(size_t capacity = 4) : capacity_(capacity == 0 ? 1 : capacity) {}

  void Push(QueuedTrigger trigger) {
    std::lock_guard lock(mutex_);
    if (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped_;
    }
    items_.push_back(trigger);
    ready_.notify_one();
  }

  // The oldest trigger, waiting up to `timeout` for one; it stays queued.
  std::optional<QueuedTrigger> Front(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [this] { return !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    return items_.front();
  }

  // Removes the oldest trigger if it is still `seq` (it may have been dropped since).
  void PopFront(int64_t seq) {
    std::lock_guard lock(mutex_);
    if (!items_.empty() && items_.front().seq == seq) items_.pop_front();
  }

  std::optional<QueuedTrigger> Pop(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    ready_.wait_for(lock, timeout, [this] { return !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    const QueuedTrigger trigger = items_.front();
    items_.pop_front();
    return trigger;
  }

  // Forgets the triggers of a closed camera: they belong to frame-sets it missed.
  void Clear() {
    std::lock_guard lock(mutex_);
    items_.clear();
  }

  int64_t Dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<QueuedTrigger> items_;
  int64_t dropped_ = 0;
};

}  // namespace shapesense
