#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/lcm/wire_check.h"

namespace shapesense {

// LCM behind a small typed interface. Subscriptions decode the raw buffer
// themselves so that a malformed message (wrong type, truncated, garbage) is
// counted and reported instead of reaching the handler; handlers must never
// throw (an exception escaping one is caught, counted, and dropped).
class LcmBus {
 public:
  // `url`: an LCM provider URL, e.g. "udpm://239.255.76.67:7667?ttl=0" or
  // "memq://"; empty uses LCM_DEFAULT_URL or LCM's default. Throws
  // std::runtime_error when LCM cannot start (no multicast route, ...).
  explicit LcmBus(const std::string& url = {});

  template <class Message>
  bool Publish(const std::string& channel, const Message& message) {
    return lcm_.publish(channel, &message) == 0;
  }

  // Handler gets the decoded message (its own: it may move from it, which
  // saves copying a camera image), the channel it came on, and the receive
  // time (µs since epoch). `channel` may be an LCM regular expression.
  template <class Message>
  void Subscribe(const std::string& channel,
                 std::function<void(Message&&, const std::string&, int64_t)> handler) {
    SubscribeRaw(channel, [handler = std::move(handler)](std::span<const uint8_t> bytes,
                                                         const std::string& channel_of,
                                                         int64_t receive_utime) {
      Message message;
      // DecodeMessage checks the lengths before lcm-gen's decoder allocates by them.
      std::string why = DecodeMessage(bytes.data(), bytes.size(), &message);
      if (why.empty()) handler(std::move(message), channel_of, receive_utime);
      return why;
    });
  }

  // Handler gets the raw bytes (valid during the call only), the channel and
  // the receive time, decodes them itself, and returns "" or why they are
  // not a valid message (counted as a rejection, as a typed subscription's
  // malformed message). For large messages read once: nothing is copied.
  using RawHandler =
      std::function<std::string(std::span<const uint8_t>, const std::string&, int64_t)>;
  void SubscribeRaw(const std::string& channel, RawHandler handler) {
    auto subscription = std::make_unique<Raw>(this, std::move(handler));
    // A plain function, not a member pointer: GCC 12's UBSan misreads LCM's
    // member-pointer subscription path (a false "misaligned address").
    lcm_.subscribeFunction(channel, &Raw::OnRawStatic, subscription.get());
    subscriptions_.push_back(std::move(subscription));
  }

  // Handles messages for up to `timeout_ms`; returns the number handled (0 or 1),
  // or -1 on an LCM error.
  int Handle(int timeout_ms) { return lcm_.handleTimeout(timeout_ms); }
  // Readable when a message waits: for a loop over several buses (poll()).
  int FileDescriptor() { return lcm_.getFileno(); }
  // The provider URL it runs on, the default resolved (ResolveLcmUrl).
  const std::string& url() const { return url_; }

  int64_t Rejected() const { return rejected_.load(); }
  int64_t HandlerErrors() const { return handler_errors_.load(); }
  const std::string& LastRejection() const { return last_rejection_; }

 private:
  struct SubscriptionBase {
    virtual ~SubscriptionBase() = default;
  };

  struct Raw : SubscriptionBase {
    Raw(LcmBus* bus, RawHandler handler) : bus_(bus), handler_(std::move(handler)) {}

    static void OnRawStatic(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                            Raw* self) {
      const std::span<const uint8_t> bytes(static_cast<const uint8_t*>(buffer->data),
                                           buffer->data_size);
      try {
        const std::string why = self->handler_(bytes, channel, buffer->recv_utime);
        if (!why.empty()) self->bus_->Reject(channel, why);
      } catch (...) {
        ++self->bus_->handler_errors_;
      }
    }

    LcmBus* bus_;
    RawHandler handler_;
  };

  void Reject(const std::string& channel, const std::string& why);

  std::string url_;
  lcm::LCM lcm_;
  std::vector<std::unique_ptr<SubscriptionBase>> subscriptions_;
  std::atomic<int64_t> rejected_{0};
  std::atomic<int64_t> handler_errors_{0};
  std::string last_rejection_;
};

// Microseconds since the Unix epoch, the time base of every LCM message.
int64_t NowUtime();

// LCM's default provider when `url` is empty: $LCM_DEFAULT_URL, else LCM's
// own default (udpm://239.255.76.67:7667?ttl=0); `url` itself otherwise.
std::string ResolveLcmUrl(const std::string& url);

}  // namespace shapesense
