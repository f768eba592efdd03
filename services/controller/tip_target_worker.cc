#include "services/controller/tip_target_worker.h"

#include <chrono>

namespace shapesense {

TipTargetWorker::TipTargetWorker(const TargetResolver& resolver)
    : resolver_(resolver), thread_([this] { Run(); }) {}

TipTargetWorker::~TipTargetWorker() {
  stopping_ = true;  // what is still queued is dropped
  jobs_.Close();
  thread_.join();
}

bool TipTargetWorker::Submit(const Job& job) {
  {
    std::lock_guard lock(mutex_);
    ++submitted_;
  }
  if (jobs_.Push(job)) return true;
  std::lock_guard lock(mutex_);
  ++finished_;  // the dropped one will never finish
  return false;
}

std::vector<TipTargetWorker::Result> TipTargetWorker::TakeResults() {
  std::lock_guard lock(mutex_);
  std::vector<Result> results(std::make_move_iterator(results_.begin()),
                              std::make_move_iterator(results_.end()));
  results_.clear();
  return results;
}

bool TipTargetWorker::busy() const {
  std::lock_guard lock(mutex_);
  return finished_ < submitted_;
}

void TipTargetWorker::Run() {
  // Pop also returns nothing on a timeout; the flag tells a closed queue.
  while (!stopping_.load()) {
    std::optional<Job> job = jobs_.Pop(std::chrono::milliseconds(100));
    if (!job || stopping_.load()) continue;
    Result result{job->receipt, resolver_.Resolve(job->target)};
    std::lock_guard lock(mutex_);
    results_.push_back(std::move(result));
    ++finished_;
  }
}

}  // namespace shapesense
