#pragma once

// What comes back from the live pipeline to the latency bench: the shapes
// (with LCM's receive time) and the latest status of each service, gathered
// by a thread handling the bus.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "runtime/lcm/lcm_bus.h"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"
#include "tests/bench/latency_stats.h"

namespace shapesense::bench {

class PipelineListener {
 public:
  // Subscribes to the shapes and every service's status on `url` and starts handling.
  explicit PipelineListener(const std::string& url);
  ~PipelineListener();
  PipelineListener(const PipelineListener&) = delete;
  PipelineListener& operator=(const PipelineListener&) = delete;

  // The shapes of trigger sequences [first, end).
  std::vector<ShapeSample> Shapes(int64_t first, int64_t end) const;
  size_t CountShapes(int64_t first, int64_t end) const;
  // The service's latest status ("carving", "shape"), if any came.
  std::optional<service_status_t> Status(const std::string& service) const;

 private:
  void OnShape(const shape_t& shape, int64_t receive_utime);
  void OnStatus(const service_status_t& status);

  LcmBus bus_;
  mutable std::mutex mutex_;
  std::map<int64_t, ShapeSample> shapes_;
  std::map<std::string, service_status_t> statuses_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Waits (bounded) until both services have published a status after `after_utime`.
bool WaitForStatuses(const PipelineListener& listener, int64_t after_utime,
                     std::chrono::milliseconds timeout);

}  // namespace shapesense::bench
