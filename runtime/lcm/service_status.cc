#include "runtime/lcm/service_status.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "runtime/host_clock.h"
#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

// CPU time this process has used, s (/proc/self/stat: utime + stime).
double ProcessCpuSeconds() {
  std::ifstream stat("/proc/self/stat");
  std::string text;
  std::getline(stat, text);
  // Fields after the command name (which may hold spaces) start past ')'.
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return 0.0;
  unsigned long user = 0;
  unsigned long system = 0;
  if (std::sscanf(text.c_str() + close + 1, " %*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu",
                  &user, &system) != 2) {
    return 0.0;
  }
  return static_cast<double>(user + system) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

int64_t ResidentBytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size = 0;
  int64_t resident = 0;
  statm >> size >> resident;
  return resident * sysconf(_SC_PAGESIZE);
}

std::string ClockWarning(const std::vector<HostClockOffset>& offsets, double threshold_ms) {
  std::string warning;
  for (const HostClockOffset& offset : offsets) {
    const double ms = static_cast<double>(offset.offset_us) * 1e-3;
    if (std::abs(ms) <= threshold_ms) continue;
    char text[160];
    std::snprintf(text, sizeof(text), "%s%s's clock is %+.3f ms off this host's (> %.3g ms)",
                  warning.empty() ? "" : "; ", offset.host.c_str(), ms, threshold_ms);
    warning += text;
  }
  return warning;
}

}  // namespace

ServiceStatus::ServiceStatus(std::string service)
    : service_(std::move(service)),
      host_(HostName()),
      start_utime_(HostUtime()),
      last_cpu_seconds_(ProcessCpuSeconds()) {}

void ServiceStatus::FillProcess(service_status_t* status, int64_t now_utime) {
  status->pid = static_cast<int32_t>(getpid());
  status->uptime_s = static_cast<double>(now_utime - start_utime_) * 1e-6;
  const double cpu = ProcessCpuSeconds();
  const double wall = static_cast<double>(now_utime - last_cpu_utime_) * 1e-6;
  if (last_cpu_utime_ > 0 && wall > 0) {
    status->cpu_percent = static_cast<float>(100.0 * (cpu - last_cpu_seconds_) / wall);
  }
  status->rss_bytes = ResidentBytes();
}

void ServiceStatus::FillClocks(service_status_t* status,
                               const std::vector<HostClockOffset>& offsets) {
  status->num_clock_offsets = static_cast<int32_t>(offsets.size());
  for (const HostClockOffset& offset : offsets) {
    status->clock_offset_hosts.push_back(offset.host);
    status->clock_offsets_us.push_back(offset.offset_us);
  }
}

void ServiceStatus::FillAuth(service_status_t* status, const AuthCounts& counts) {
  status->auth = counts.mode;
  status->auth_accepted = counts.accepted;
  status->num_auth_rejections = static_cast<int32_t>(counts.rejections.size());
  for (const auto& [reason, count] : counts.rejections) {
    status->auth_rejection_reasons.push_back(reason);
    status->auth_rejections.push_back(count);
  }
  status->estops_accepted_unsigned = counts.estops_accepted_unsigned;
}

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
  FillProcess(&status, now_utime);
  return status;
}

void ServiceStatus::MaybePublish(LcmBus& bus, int64_t now_utime, int64_t also_rejected) {
  if (last_utime_ > 0 && now_utime - last_utime_ < 1'000'000) return;
  Publish(bus, now_utime, also_rejected);
}

void ServiceStatus::Publish(LcmBus& bus, int64_t now_utime, int64_t also_rejected) {
  ListenToPeers(bus);
  const std::vector<HostClockOffset> offsets = bus.clock_offsets().Snapshot();
  const std::string warning = ClockWarning(offsets, bus.options().clock_warning_ms);
  if (!warning.empty() && warning != last_clock_warning_) Note(warning);
  last_clock_warning_ = warning;
  service_status_t status = Snapshot(now_utime, bus.Rejected() + also_rejected);
  status.host = bus.host();  // the name its messages carry
  FillClocks(&status, offsets);
  status.clock_warning = warning;
  FillAuth(&status, bus.AuthSnapshot());
  bus.Publish(channels::Status(service_), status);
  last_cpu_utime_ = now_utime;
  last_cpu_seconds_ = ProcessCpuSeconds();
  std::lock_guard lock(mutex_);
  ++seq_;
  last_utime_ = now_utime;
  last_received_ = status.received;
  last_published_ = status.published;
}

// Every program hears the others' status (1 Hz each): the traffic its
// estimate of their clocks' offsets comes from, even when it reads nothing
// else of theirs. The bus observes every message's host and times itself.
void ServiceStatus::ListenToPeers(LcmBus& bus) {
  if (listening_to_ == &bus) return;
  listening_to_ = &bus;
  bus.Subscribe<service_status_t>(channels::kStatusPattern,
                                  [](service_status_t&&, const std::string&, int64_t) {});
}

}  // namespace shapesense
