#include "runtime/lcm/service_status.h"

#include <unistd.h>

#include <array>

#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

std::string HostName() {
  std::array<char, 256> name{};
  if (gethostname(name.data(), name.size() - 1) != 0) return "unknown";
  return name.data();
}

}  // namespace

ServiceStatus::ServiceStatus(std::string service)
    : service_(std::move(service)), host_(HostName()) {}

void ServiceStatus::Error(const std::string& what) {
  ++errors_;
  std::lock_guard lock(mutex_);
  last_error_ = what;
}

void ServiceStatus::Note(const std::string& what) {
  std::lock_guard lock(mutex_);
  last_error_ = what;
}

service_status_t ServiceStatus::Snapshot(int64_t now_utime, int64_t bus_rejected) {
  std::lock_guard lock(mutex_);
  service_status_t status{};
  status.header.seq = seq_;
  status.header.utime = now_utime;
  status.service = service_;
  status.host = host_;
  const double seconds =
      last_utime_ > 0 ? static_cast<double>(now_utime - last_utime_) * 1e-6 : 0.0;
  if (seconds > 0) {
    status.input_rate_hz =
        static_cast<float>(static_cast<double>(received_ - last_received_) / seconds);
    status.output_rate_hz =
        static_cast<float>(static_cast<double>(published_ - last_published_) / seconds);
  }
  status.received = received_;
  status.published = published_;
  status.dropped = dropped_;
  status.rejected = rejected_ + bus_rejected;
  status.errors = errors_;
  status.queue_depth = queue_depth_;
  status.last_error = last_error_;
  return status;
}

void ServiceStatus::MaybePublish(LcmBus& bus, int64_t now_utime, int64_t also_rejected) {
  if (last_utime_ > 0 && now_utime - last_utime_ < 1'000'000) return;
  Publish(bus, now_utime, also_rejected);
}

void ServiceStatus::Publish(LcmBus& bus, int64_t now_utime, int64_t also_rejected) {
  const service_status_t status = Snapshot(now_utime, bus.Rejected() + also_rejected);
  bus.Publish(channels::Status(service_), status);
  std::lock_guard lock(mutex_);
  ++seq_;
  last_utime_ = now_utime;
  last_received_ = status.received;
  last_published_ = status.published;
}

}  // namespace shapesense
