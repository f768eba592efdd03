#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "runtime/lcm/bus_auth.h"
#include "runtime/lcm/channel_networks.h"
#include "runtime/lcm/clock_offsets.h"
#include "runtime/lcm/wire_check.h"

namespace shapesense {

// Where a program's LCM traffic goes: the rig network and the host-local
// one (channel_networks.h), the rig's channel prefix, this host's name.
struct LcmBusOptions {
  // The rig network; empty: $LCM_DEFAULT_URL or LCM's default.
  std::string url;
  // The host-local network (ttl=0); empty: `url` with ttl=0 (the same
  // group and port: a process on the rig network also hears the host's
  // local traffic on that port, but nothing local leaves the host).
  std::string local_url;
  // Added to every channel (channels.h): [A-Za-z0-9_]*.
  std::string prefix;
  std::vector<ChannelRoute> routes;  // before the defaults
  std::string host;                  // empty: this host's name
  // Another host's clock further off than this is warned of in the status, ms.
  double clock_warning_ms = 1.0;
  // Signing and verifying the channels that move the robot (bus_auth.h). A
  // bus whose rig network leaves the host (ttl > 0) refuses to start
  // without keys unless `auth.insecure`.
  AuthOptions auth;

  // `url` with the rest from the environment: SHAPESENSE_LOCAL_LCM_URL,
  // SHAPESENSE_RIG_PREFIX, SHAPESENSE_CHANNEL_NETWORKS,
  // SHAPESENSE_CLOCK_WARNING_MS, SHAPESENSE_KEY_FILES, SHAPESENSE_INSECURE
  // (what a rig's unit files set: `shapesense rig units`). Throws
  // std::invalid_argument naming the variable on a bad value.
  static LcmBusOptions FromEnvironment(const std::string& url = {});
};

// LCM behind a small typed interface, over the rig network and the
// host-local one. Subscriptions decode the raw buffer themselves so that a
// malformed message (wrong type, truncated, garbage) is counted and reported
// instead of reaching the handler; handlers must never throw (an exception
// escaping one is caught, counted, and dropped). Every message published
// names this host (header.host); every message received from another host
// feeds the estimate of that host's clock offset (clock_offsets()). With
// keys, messages on the signed channels (bus_auth.h) are signed as they are
// published and reach a handler only when authentic and fresh.
class LcmBus {
  // Every shapesense message has a header_t; tests also send bare types.
  template <class Message>
  static constexpr bool kHasHeader = requires(Message message) {
    message.header.host;
  };

 public:
  // `url`: an LCM provider URL, e.g. "udpm://239.255.76.67:7667?ttl=0" or
  // "memq://"; the rest from the environment (LcmBusOptions::FromEnvironment).
  // Throws std::runtime_error when LCM cannot start (no multicast route, ...).
  explicit LcmBus(const std::string& url = {});
  explicit LcmBus(const LcmBusOptions& options);
  ~LcmBus();
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  // Publishes on the channel's network, naming this host when the message
  // does not name one, signed when the channel is. Refuses (false, counted
  // in Refused()) a message larger than one datagram on a rig network that
  // leaves the host (ttl > 0), unless its channel is tolerant to loss.
  template <class Message>
  bool Publish(const std::string& channel, Message& message) {
    if constexpr (kHasHeader<Message>) {
      if (message.header.host.empty()) message.header.host = host_;
    }
    return PublishNamed(channel, message);
  }
  // A const message without a host is copied to be named: publish a
  // mutable one where it is large (an image).
  template <class Message>
  bool Publish(const std::string& channel, const Message& message) {
    if constexpr (kHasHeader<Message>) {
      if (message.header.host.empty()) {
        Message named = message;
        named.header.host = host_;
        return PublishNamed(channel, named);
      }
    }
    return PublishNamed(channel, message);
  }

  // Handler gets the decoded message (its own: it may move from it, which
  // saves copying a camera image), the channel it came on (without the rig
  // prefix), and the receive time (µs since epoch, this host's clock).
  // `channel` may be an LCM regular expression.
  template <class Message>
  void Subscribe(const std::string& channel,
                 std::function<void(Message&&, const std::string&, int64_t)> handler) {
    const int subscription = static_cast<int>(subscriptions_.size());
    SubscribeRaw(channel, [this, subscription, handler = std::move(handler)](
                              std::span<const uint8_t> bytes, const std::string& channel_of,
                              int64_t receive_utime) {
      Message message;
      // DecodeMessage checks the lengths before lcm-gen's decoder allocates by them.
      std::string why = DecodeMessage(bytes.data(), bytes.size(), &message);
      if (!why.empty()) return why;
      if constexpr (kHasHeader<Message>) {
        why = Authenticate(subscription, channel_of, bytes, message, receive_utime);
        if (!why.empty()) return why;
        ObserveClock(message.header.host, message.header.utime, receive_utime);
      }
      handler(std::move(message), channel_of, receive_utime);
      return why;
    });
  }

  // Handler gets the raw bytes (valid during the call only), the channel
  // (without the prefix) and the receive time, decodes them itself, and
  // returns "" or why they are not a valid message (counted as a rejection,
  // as a typed subscription's malformed message). For large messages read
  // once: nothing is copied.
  using RawHandler =
      std::function<std::string(std::span<const uint8_t>, const std::string&, int64_t)>;
  void SubscribeRaw(const std::string& channel, RawHandler handler);

  // Handles messages for up to `timeout_ms`; returns the number handled,
  // or -1 on an LCM error.
  int Handle(int timeout_ms);
  // Readable when a message waits: for a loop over several buses (poll()).
  std::vector<int> FileDescriptors();
  // The provider URLs it runs on, defaults resolved.
  const std::string& url() const { return url_; }
  const std::string& local_url() const { return local_url_; }
  const LcmBusOptions& options() const { return options_; }
  const std::string& host() const { return host_; }
  const ClockOffsets& clock_offsets() const { return clock_offsets_; }
  // Whether this bus signs and verifies, and what it rejected.
  AuthCounts AuthSnapshot() const { return auth_->Counts(); }

  int64_t Rejected() const { return rejected_.load(); }
  int64_t HandlerErrors() const { return handler_errors_.load(); }
  int64_t Refused() const { return refused_.load(); }
  std::string LastRejection() const;

 private:
  struct Raw {
    LcmBus* bus;
    RawHandler handler;
    static void OnRawStatic(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                            Raw* self);
  };

  template <class Message>
  bool PublishNamed(const std::string& channel, const Message& message) {
    lcm::LCM& target = PublishTarget(channel);
    const bool checked = &target == rig_.get() && leaves_host_;
    if (checked && !FitsRigNetwork(channel, message.getEncodedSize())) return false;
    const std::string wire_channel = options_.prefix + channel;
    if constexpr (kHasHeader<Message>) {
      if (auth_->on() && IsSignedChannel(channel)) {
        return auth_->SignAndSend(wire_channel, message, [&](std::span<const uint8_t> bytes) {
          // Signed, it names its sender: a few bytes more.
          const int size = static_cast<int>(bytes.size());
          if (checked && !FitsRigNetwork(channel, size)) return false;
          return target.publish(wire_channel, bytes.data(), static_cast<unsigned>(size)) == 0;
        });
      }
    }
    return target.publish(wire_channel, &message) == 0;
  }
  // "" when `message` may reach its handler; otherwise why not.
  template <class Message>
  std::string Authenticate(int subscription, const std::string& channel,
                           std::span<const uint8_t> bytes, const Message& message,
                           int64_t receive_utime) {
    if (!IsSignedChannel(channel)) return {};
    return auth_->Admit(subscription, options_.prefix + channel, bytes, message, receive_utime);
  }
  bool FitsRigNetwork(const std::string& channel, int encoded_bytes) {
    if (IsLossTolerant(channel) || encoded_bytes <= MaxRigMessageBytes(channel)) return true;
    Refuse(channel, encoded_bytes);
    return false;
  }

  lcm::LCM& PublishTarget(const std::string& channel);
  std::vector<lcm::LCM*> Receivers(const std::string& channel);
  void ObserveClock(const std::string& host, int64_t send_utime, int64_t receive_utime);
  void Reject(const std::string& channel, const std::string& why);
  void Refuse(const std::string& channel, int bytes);

  LcmBusOptions options_;
  std::string url_;
  std::string local_url_;
  std::string host_;
  ChannelNetworks networks_;
  std::unique_ptr<lcm::LCM> rig_;
  std::unique_ptr<lcm::LCM> local_;  // null when the local network is the rig's URL
  bool local_receives_ = false;      // local_ on a port of its own, with subscriptions
  bool leaves_host_ = false;         // the rig network's ttl > 0
  std::vector<std::unique_ptr<Raw>> subscriptions_;
  ClockOffsets clock_offsets_;
  std::unique_ptr<BusAuth> auth_;
  std::atomic<int64_t> rejected_{0};
  std::atomic<int64_t> handler_errors_{0};
  std::atomic<int64_t> refused_{0};
  mutable std::mutex mutex_;
  std::string last_rejection_;
};

// Microseconds since the Unix epoch on this host's clock (host_clock.h),
// the time base of every LCM message.
int64_t NowUtime();

// LCM's default provider when `url` is empty: $LCM_DEFAULT_URL, else LCM's
// own default (udpm://239.255.76.67:7667?ttl=0); `url` itself otherwise.
std::string ResolveLcmUrl(const std::string& url);

}  // namespace shapesense
