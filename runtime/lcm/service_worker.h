#pragma once

// The bounded queue and the one worker thread behind every LCM service: the
// bus thread pushes jobs and never blocks; on overload the oldest job is
// dropped and counted; a job that throws is counted as an error, and the
// worker goes on with the next.
#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>
#include <utility>

#include "runtime/lcm/bounded_queue.h"
#include "runtime/lcm/service_status.h"

namespace shapesense {

template <class Job>
class ServiceWorker {
 public:
  using Process = std::function<void(Job& job)>;
  using Describe = std::function<std::string(const Job& job)>;

  // Starts the worker at once: declare the ServiceWorker as the service's
  // last member, so that everything `process` uses exists before it starts
  // and is still there until the destructor has joined it. `job_kind` names
  // a job in the status ("frame-set", "voxel cloud").
  ServiceWorker(int capacity, ServiceStatus& status, std::string job_kind, Describe describe,
                Process process)
      : queue_(static_cast<size_t>(capacity)),
        status_(status),
        job_kind_(std::move(job_kind)),
        describe_(std::move(describe)),
        process_(std::move(process)),
        thread_([this] { Run(); }) {}

  ~ServiceWorker() {
    stopping_ = true;
    queue_.Close();
    thread_.join();
  }
  ServiceWorker(const ServiceWorker&) = delete;
  ServiceWorker& operator=(const ServiceWorker&) = delete;

  // From the bus thread.
  void Push(Job job) {
    if (!queue_.Push(std::move(job))) {
      status_.Dropped();
      status_.Note("overload: the oldest waiting " + job_kind_ + " was dropped");
    }
    status_.SetQueueDepth(static_cast<int>(queue_.Size()));
  }

  int depth() const { return static_cast<int>(queue_.Size()); }
  // Whether one job has held the worker for longer than `limit` (a hang,
  // which a watchdog should see: SystemdNotifier::SetHealthCheck).
  bool BusyLongerThan(std::chrono::microseconds limit) const {
    const int64_t since = busy_since_us_.load();
    return since != 0 && SteadyUs() - since > limit.count();
  }

 private:
  void Run() {
    while (!stopping_) {
      std::optional<Job> job = queue_.Pop(std::chrono::milliseconds(100));
      if (!job) continue;
      status_.SetQueueDepth(static_cast<int>(queue_.Size()));
      busy_since_us_ = SteadyUs();
      try {
        process_(*job);
      } catch (const std::exception& e) {
        status_.Error(describe_(*job) + ": " + e.what());
      }
      busy_since_us_ = 0;
    }
  }

  BoundedQueue<Job> queue_;
  ServiceStatus& status_;
  const std::string job_kind_;
  const Describe describe_;
  const Process process_;
  static int64_t SteadyUs() {
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  std::atomic<bool> stopping_{false};
  std::atomic<int64_t> busy_since_us_{0};  // steady µs the current job started; 0: idle
  std::thread thread_;                     // last: starts once everything above exists
};

}  // namespace shapesense
