#include "services/rig_sim/actuators/simulated_serial_actuator.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>

#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

using serial_protocol::DeviceError;

constexpr int kPollMs = 5;

std::string ErrorReply(DeviceError code, const std::string& text) {
  return "E " + std::to_string(static_cast<int>(code)) + " " + text;
}

// Makes the checksum of an encoded line wrong (its last hex digit changes).
void CorruptChecksum(std::string* line) {
  char& digit = (*line)[line->size() - 2];
  digit = digit == '0' ? '1' : '0';
}

}  // namespace

SimulatedSerialActuator::SimulatedSerialActuator(int fd, SimulatedSerialActuatorOptions options)
    : fd_(fd), options_(std::move(options)), axes_(static_cast<size_t>(options_.axes)) {
  last_advance_us_ = last_valid_line_us_ = SteadyMicros();
}

SimulatedSerialActuator::~SimulatedSerialActuator() { Stop(); }

void SimulatedSerialActuator::Start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] { Serve(); });
}

void SimulatedSerialActuator::Stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void SimulatedSerialActuator::Serve() {
  serial_protocol::LineAssembler assembler;
  while (running_) ServeOnce(assembler);
}

void SimulatedSerialActuator::ServeOnce(serial_protocol::LineAssembler& assembler) {
  pollfd entry{fd_, POLLIN, 0};
  const int ready = poll(&entry, 1, kPollMs);
  std::vector<std::string> lines;
  if (ready > 0 && (entry.revents & POLLIN)) {
    char buffer[512];
    const ssize_t got = read(fd_, buffer, sizeof(buffer));
    if (got > 0) assembler.Feed(std::string_view(buffer, static_cast<size_t>(got)), &lines);
  } else if (ready > 0) {
    usleep(kPollMs * 1000);  // no driver at the other end (or the fd closed): wait for one
  }
  for (const std::string& line : lines) WriteReply(HandleLine(line, SteadyMicros()));
  std::lock_guard lock(mutex_);
  AdvanceLocked(SteadyMicros());
}

void SimulatedSerialActuator::WriteReply(const std::string& reply) {
  {
    std::lock_guard lock(mutex_);
    if (muted_ || reply.empty()) return;
  }
  std::string_view rest = reply;
  for (int attempt = 0; attempt < 20 && !rest.empty(); ++attempt) {
    const ssize_t written = write(fd_, rest.data(), rest.size());
    if (written > 0) {
      rest.remove_prefix(static_cast<size_t>(written));
    } else if (written < 0 && errno != EAGAIN && errno != EINTR) {
      return;  // the link is gone; the driver will notice
    } else {
      pollfd entry{fd_, POLLOUT, 0};
      poll(&entry, 1, kPollMs);
    }
  }
}

std::string SimulatedSerialActuator::HandleLine(std::string_view line, int64_t now_us) {
  std::lock_guard lock(mutex_);
  ++counters_.lines;
  std::string received(line);
  if (corrupt_requests_ > 0 && !received.empty()) {
    --corrupt_requests_;
    received[0] = static_cast<char>(received[0] ^ 0x20);
  }
  const serial_protocol::DecodedLine decoded = serial_protocol::DecodeLine(received);
  std::string reply_body;
  if (!decoded.ok()) {
    ++counters_.checksum_errors;
    reply_body = ErrorReply(DeviceError::kChecksum, decoded.error);
  } else {
    AdvanceLocked(now_us);
    last_valid_line_us_ = now_us;
    watchdog_tripped_ = false;
    reply_body = ReplyLocked(serial_protocol::SplitWords(decoded.body));
  }
  std::string reply = serial_protocol::EncodeLine(reply_body);
  if (corrupt_replies_ > 0) {
    --corrupt_replies_;
    CorruptChecksum(&reply);
  }
  return reply;
}

std::string SimulatedSerialActuator::ReplyLocked(const std::vector<std::string>& words) {
  const std::string command = words.empty() ? "" : words[0];
  if (command == "I?" && words.size() == 1) {
    return "I " + std::to_string(options_.axes) + " " + options_.name;
  }
  if (command == "T") return TargetLocked(words);
  if (command == "P?" && words.size() == 1) return PositionsLocked();
  if (command == "S?" && words.size() == 1) {
    if (fault_code_ == 0) return "S OK";
    return "S FAULT " + std::to_string(fault_code_) + " " + fault_reason_;
  }
  if (command == "X" && words.size() == 1) {
    ++counters_.stops;
    for (AxisMotion& axis : axes_) axis.Hold();
    return "X";
  }
  if (command == "R" && words.size() == 1) {
    fault_code_ = 0;
    fault_reason_.clear();
    return "R";
  }
  if (command == "W") return WatchdogLocked(words);
  return ErrorReply(DeviceError::kSyntax, "unknown command '" + command + "'");
}

std::string SimulatedSerialActuator::TargetLocked(const std::vector<std::string>& words) {
  const auto refuse = [&](DeviceError code, const std::string& text) {
    ++counters_.refused_targets;
    return ErrorReply(code, text);
  };
  if (words.size() != 3) return refuse(DeviceError::kSyntax, "expected T <axis> <mm>");
  const std::optional<int> axis = serial_protocol::ParseInteger(words[1]);
  const std::optional<double> mm = serial_protocol::ParseNumber(words[2]);
  if (!axis || !mm) return refuse(DeviceError::kSyntax, "expected T <axis> <mm>");
  const int index = axis.value_or(-1);
  const double target = mm.value_or(0.0);
  if (index < 0 || index >= options_.axes) return refuse(DeviceError::kAxis, "no axis " + words[1]);
  if (std::abs(target) > options_.travel_mm) {
    return refuse(DeviceError::kRange, "target " + words[2] + " outside +-" +
                                           serial_protocol::FormatMm(options_.travel_mm));
  }
  if (fault_code_ != 0) return refuse(DeviceError::kFaulted, "faulted: " + fault_reason_);
  ++counters_.targets;
  axes_[static_cast<size_t>(index)].target = target;
  return "T " + words[1] + " " + serial_protocol::FormatMm(target);
}

std::string SimulatedSerialActuator::WatchdogLocked(const std::vector<std::string>& words) {
  const std::optional<int> ms =
      words.size() == 2 ? serial_protocol::ParseInteger(words[1]) : std::nullopt;
  if (!ms || *ms < 0) return ErrorReply(DeviceError::kSyntax, "expected W <ms>");
  watchdog_us_ = static_cast<int64_t>(*ms) * 1000;
  return "W " + std::to_string(*ms);
}

std::string SimulatedSerialActuator::PositionsLocked() const {
  std::string reply = "P";
  for (const AxisMotion& axis : axes_) {
    reply += ' ';
    reply += serial_protocol::FormatMm(axis.position);
  }
  return reply;
}

void SimulatedSerialActuator::AdvanceLocked(int64_t now_us) {
  const int64_t expiry_us = last_valid_line_us_ + watchdog_us_;
  if (watchdog_us_ > 0 && !watchdog_tripped_ && now_us > expiry_us) {
    // The controller went quiet: hold where the axes were when it expired
    // rather than keep moving on an old target.
    MoveLocked(expiry_us);
    watchdog_tripped_ = true;
    ++counters_.watchdog_stops;
    for (AxisMotion& axis : axes_) axis.Hold();
  }
  MoveLocked(now_us);
}

void SimulatedSerialActuator::MoveLocked(int64_t until_us) {
  const double dt = static_cast<double>(until_us - last_advance_us_) * 1e-6;
  if (dt <= 0.0) return;
  last_advance_us_ = until_us;
  for (AxisMotion& axis : axes_) axis.Advance(dt, options_.max_speed_mm_s);
}

void SimulatedSerialActuator::InjectFault(int code, const std::string& reason) {
  std::lock_guard lock(mutex_);
  fault_code_ = code;
  fault_reason_ = reason;
  for (AxisMotion& axis : axes_) axis.Hold();
}

void SimulatedSerialActuator::CorruptReplies(int count) {
  std::lock_guard lock(mutex_);
  corrupt_replies_ = count;
}

void SimulatedSerialActuator::CorruptRequests(int count) {
  std::lock_guard lock(mutex_);
  corrupt_requests_ = count;
}

void SimulatedSerialActuator::SetMuted(bool muted) {
  std::lock_guard lock(mutex_);
  muted_ = muted;
}

std::vector<double> SimulatedSerialActuator::positions() const {
  std::lock_guard lock(mutex_);
  std::vector<double> result;
  for (const AxisMotion& axis : axes_) result.push_back(axis.position);
  return result;
}

std::vector<double> SimulatedSerialActuator::targets() const {
  std::lock_guard lock(mutex_);
  std::vector<double> result;
  for (const AxisMotion& axis : axes_) result.push_back(axis.target);
  return result;
}

SimulatedSerialActuator::Counters SimulatedSerialActuator::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

}  // namespace shapesense
