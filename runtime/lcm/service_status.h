#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>

#include "runtime/lcm/lcm_bus.h"
#include "shapesense/service_status_t.hpp"

namespace shapesense {

// Counters of one service, safe to bump from any thread, published at 1 Hz
// on channels::Status(service) by MaybePublish.
class ServiceStatus {
 public:
  explicit ServiceStatus(std::string service);

  void Received(int64_t n = 1) { received_ += n; }
  void Published(int64_t n = 1) { published_ += n; }
  void Dropped(int64_t n = 1) { dropped_ += n; }
  void Rejected(int64_t n = 1) { rejected_ += n; }
  void Error(const std::string& what);
  // Records `what` as the last error without counting an error (e.g. why a
  // message was rejected or a frame-set dropped, next to that counter).
  void Note(const std::string& what);
  void SetQueueDepth(int depth) { queue_depth_ = depth; }

  // Publishes when at least a second has passed since the last status;
  // `bus_rejected` adds the bus's count of malformed messages.
  // `also_rejected`: messages that other buses of the service refused.
  void MaybePublish(LcmBus& bus, int64_t now_utime, int64_t also_rejected = 0);
  // Publishes now, however recent the last status (a service's last status
  // as it stops, so that its final counts reach the network).
  void Publish(LcmBus& bus, int64_t now_utime, int64_t also_rejected = 0);
  // The message as it would be published now (for tests and logs).
  service_status_t Snapshot(int64_t now_utime, int64_t bus_rejected = 0);

  int64_t received() const { return received_; }
  int64_t published() const { return published_; }
  int64_t dropped() const { return dropped_; }
  int64_t errors() const { return errors_; }

 private:
  void FillProcess(service_status_t* status, int64_t now_utime);
  static void FillClocks(service_status_t* status, const std::vector<HostClockOffset>& offsets);
  static void FillAuth(service_status_t* status, const AuthCounts& counts);
  void ListenToPeers(LcmBus& bus);

  std::string service_;
  std::string host_;
  int64_t start_utime_ = 0;
  int64_t last_cpu_utime_ = 0;
  double last_cpu_seconds_ = 0.0;
  std::string last_clock_warning_;
  const LcmBus* listening_to_ = nullptr;
  std::atomic<int64_t> received_{0}, published_{0}, dropped_{0}, rejected_{0}, errors_{0};
  std::atomic<int> queue_depth_{0};
  std::mutex mutex_;
  std::string last_error_;
  int64_t seq_ = 0;
  int64_t last_utime_ = 0;
  int64_t last_received_ = 0;
  int64_t last_published_ = 0;
};

}  // namespace shapesense
