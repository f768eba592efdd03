#pragma once

// Resolves streamed tip-position targets off the control thread. The tip
// solver (libs/control/tip_solver.h) runs Levenberg-Marquardt from several
// starts: ~45 ms for a tip near the edge of the workspace (measured on the
// build machine), several control periods during which the loop would
// neither command nor see an e-stop. Configuration targets are cheap and the
// control step resolves them itself.

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "libs/control/targets.h"
#include "runtime/lcm/bounded_queue.h"

namespace shapesense {

class TipTargetWorker {
 public:
  struct Job {
    int64_t receipt = 0;  // the caller's order of arrival
    Target target;
  };
  struct Result {
    int64_t receipt = 0;
    ResolvedTarget resolved;
  };

  explicit TipTargetWorker(const TargetResolver& resolver);
  // Stops the thread (a target in work is finished first, queued ones dropped).
  ~TipTargetWorker();
  TipTargetWorker(const TipTargetWorker&) = delete;
  TipTargetWorker& operator=(const TipTargetWorker&) = delete;

  // Queues a target; false when the queue was full and the oldest was dropped.
  bool Submit(const Job& job);
  // The results finished since the last call, in order.
  std::vector<Result> TakeResults();
  // Something is queued or in work.
  bool busy() const;

 private:
  void Run();

  const TargetResolver resolver_;
  BoundedQueue<Job> jobs_{8};
  mutable std::mutex mutex_;
  std::deque<Result> results_;
  int64_t submitted_ = 0;  // guarded by mutex_
  int64_t finished_ = 0;   // guarded by mutex_, dropped jobs included
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace shapesense
