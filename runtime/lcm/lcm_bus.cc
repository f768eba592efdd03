#include "runtime/lcm/lcm_bus.h"

#include <poll.h>

#include <atomic>
#include <cstdlib>
#include <iostream>
#include <stdexcept>

#include "runtime/host_clock.h"
#include "runtime/lcm/lcm_url.h"
#include "runtime/security/key_file.h"

namespace shapesense {
namespace {

std::string Environment(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}

void CheckPrefix(const std::string& prefix) {
  for (const char c : prefix) {
    const bool allowed =
        (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    if (!allowed) {
      throw std::invalid_argument("rig prefix '" + prefix +
                                  "': only letters, digits and '_' (it starts LCM channel "
                                  "names and their regular expressions)");
    }
  }
}

std::unique_ptr<lcm::LCM> StartLcm(const std::string& url, const std::string& given) {
  auto instance = std::make_unique<lcm::LCM>(url);
  if (!instance->good()) {
    throw std::runtime_error("LCM could not start on '" +
                             (given.empty() ? std::string("default") : url) +
                             "' (is there a multicast route? see docs/rig.md, section Multicast)");
  }
  return instance;
}

// The rig network's URL kept on the host (one network when it is local already).
std::string LocalUrlOf(const std::string& url) { return TtlOf(url) == 0 ? url : WithTtl(url, 0); }

// Buses of this process so far: each signs under a name of its own.
std::atomic<int> buses_made{0};

void WarnInsecure(const std::string& url) {
  static std::once_flag warned;
  std::call_once(warned, [&] {
    std::cerr << "\n"
                 "**********************************************************************\n"
                 "  WARNING: message authentication is OFF (insecure).\n"
                 "  Any host that reaches "
              << url
              << "\n"
                 "  can send targets, commands and shapes that move the tendons.\n"
                 "  Give the rig key instead: SHAPESENSE_KEY_FILES (docs/security.md).\n"
                 "**********************************************************************\n\n";
  });
}

// The bus's authentication: keys when given; none on a host-local network;
// refused on a network that leaves the host, unless insecure (loudly).
std::unique_ptr<BusAuth> MakeAuth(const AuthOptions& options, const std::string& url,
                                  bool leaves_host, const std::string& host) {
  const std::string sender =
      options.sender.empty() ? DefaultSender(host, buses_made++) : options.sender;
  if (!options.key_files.empty()) {
    return std::make_unique<BusAuth>(ReadKeyRing(options.key_files), sender, options.first_contact,
                                     "");
  }
  if (!leaves_host)
    return std::make_unique<BusAuth>(std::nullopt, sender, FirstContactRule{}, "off (host-local)");
  if (options.read_only)
    return std::make_unique<BusAuth>(std::nullopt, sender, FirstContactRule{}, "off (read-only)");
  if (!options.insecure) {
    throw std::invalid_argument(
        "the rig network " + url +
        " leaves this host (ttl > 0) and no key is given: set SHAPESENSE_KEY_FILES to the "
        "rig's key file (`shapesense keygen`, docs/security.md), or SHAPESENSE_INSECURE=1 to "
        "run without authentication");
  }
  WarnInsecure(url);
  return std::make_unique<BusAuth>(std::nullopt, sender, FirstContactRule{}, "OFF (insecure)");
}

}  // namespace

AuthOptions AuthOptions::FromEnvironment() {
  AuthOptions options;
  options.key_files = ParseKeyFiles(Environment("SHAPESENSE_KEY_FILES"));
  const std::string insecure = Environment("SHAPESENSE_INSECURE");
  if (!insecure.empty() && insecure != "0" && insecure != "1") {
    throw std::invalid_argument("SHAPESENSE_INSECURE='" + insecure + "': expected 0 or 1");
  }
  options.insecure = insecure == "1";
  options.sender = Environment("SHAPESENSE_AUTH_SENDER");
  return options;
}

LcmBusOptions LcmBusOptions::FromEnvironment(const std::string& url) {
  LcmBusOptions options;
  options.url = url;
  options.local_url = Environment("SHAPESENSE_LOCAL_LCM_URL");
  options.prefix = Environment("SHAPESENSE_RIG_PREFIX");
  if (const std::string ms = Environment("SHAPESENSE_CLOCK_WARNING_MS"); !ms.empty()) {
    char* end = nullptr;
    options.clock_warning_ms = std::strtod(ms.c_str(), &end);
    if (*end != 0 || !(options.clock_warning_ms > 0)) {
      throw std::invalid_argument("SHAPESENSE_CLOCK_WARNING_MS='" + ms +
                                  "': expected a positive number of milliseconds");
    }
  }
  try {
    options.routes = ChannelNetworks::Parse(Environment("SHAPESENSE_CHANNEL_NETWORKS"));
  } catch (const std::invalid_argument& error) {
    throw std::invalid_argument(std::string("SHAPESENSE_CHANNEL_NETWORKS: ") + error.what());
  }
  options.auth = AuthOptions::FromEnvironment();
  return options;
}

LcmBus::LcmBus(const std::string& url) : LcmBus(LcmBusOptions::FromEnvironment(url)) {}

LcmBus::LcmBus(const LcmBusOptions& options)
    : options_(options),
      url_(ResolveLcmUrl(options.url)),
      local_url_(options.local_url.empty() ? LocalUrlOf(url_) : options.local_url),
      host_(options.host.empty() ? HostName() : options.host),
      networks_(options.routes) {
  CheckPrefix(options.prefix);
  rig_ = StartLcm(url_, options.url);
  if (local_url_ != url_) local_ = StartLcm(local_url_, options.local_url);
  leaves_host_ = TtlOf(url_) > 0;
  auth_ = MakeAuth(options.auth, url_, leaves_host_, host_);
}

LcmBus::~LcmBus() = default;

lcm::LCM& LcmBus::PublishTarget(const std::string& channel) {
  return local_ && networks_.Of(channel) == Network::kLocal ? *local_ : *rig_;
}

// A local channel is heard on the local URL's socket, unless the local URL
// shares the rig's group and port: then the rig's socket receives it too,
// and a second socket on the port would only receive everything twice.
std::vector<lcm::LCM*> LcmBus::Receivers(const std::string& channel) {
  const bool own_port = local_ && GroupAndPort(local_url_) != GroupAndPort(url_);
  if (!own_port) return {rig_.get()};
  const bool local = IsPlainChannel(channel) ? networks_.Of(channel) == Network::kLocal
                                             : networks_.MayBeLocal(channel);
  if (!local) return {rig_.get()};
  local_receives_ = true;
  return IsPlainChannel(channel) ? std::vector<lcm::LCM*>{local_.get()}
                                 : std::vector<lcm::LCM*>{rig_.get(), local_.get()};
}

void LcmBus::SubscribeRaw(const std::string& channel, RawHandler handler) {
  auto subscription = std::make_unique<Raw>(Raw{this, std::move(handler)});
  // A plain function, not a member pointer: GCC 12's UBSan misreads LCM's
  // member-pointer subscription path (a false "misaligned address").
  for (lcm::LCM* lcm : Receivers(channel)) {
    lcm->subscribeFunction(options_.prefix + channel, &Raw::OnRawStatic, subscription.get());
  }
  subscriptions_.push_back(std::move(subscription));
}

void LcmBus::Raw::OnRawStatic(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                              Raw* self) {
  const std::span<const uint8_t> bytes(static_cast<const uint8_t*>(buffer->data),
                                       buffer->data_size);
  const std::string& prefix = self->bus->options_.prefix;
  // No copy of the name per message (an image's too) without a prefix.
  std::string stripped;
  if (!prefix.empty()) stripped = channel.substr(std::min(prefix.size(), channel.size()));
  const std::string& unprefixed = prefix.empty() ? channel : stripped;
  // LCM stamps receipt with the system clock; this host's clock may carry
  // the tests' offset.
  const int64_t receive_utime = buffer->recv_utime + TestClockOffsetUs();
  try {
    const std::string why = self->handler(bytes, unprefixed, receive_utime);
    if (!why.empty()) self->bus->Reject(unprefixed, why);
  } catch (...) {
    ++self->bus->handler_errors_;
  }
}

int LcmBus::Handle(int timeout_ms) {
  if (!local_receives_) return rig_->handleTimeout(timeout_ms);
  std::vector<pollfd> waiting = {{rig_->getFileno(), POLLIN, 0}, {local_->getFileno(), POLLIN, 0}};
  const int ready = ::poll(waiting.data(), waiting.size(), timeout_ms);
  if (ready < 0) return errno == EINTR ? 0 : -1;
  int handled = 0;
  if ((waiting[0].revents & POLLIN) != 0) handled += rig_->handle() == 0 ? 1 : 0;
  if ((waiting[1].revents & POLLIN) != 0) handled += local_->handle() == 0 ? 1 : 0;
  return handled;
}

std::vector<int> LcmBus::FileDescriptors() {
  if (!local_receives_) return {rig_->getFileno()};
  return {rig_->getFileno(), local_->getFileno()};
}

void LcmBus::ObserveClock(const std::string& host, int64_t send_utime, int64_t receive_utime) {
  if (!host.empty() && host != host_) clock_offsets_.Observe(host, send_utime, receive_utime);
}

void LcmBus::Reject(const std::string& channel, const std::string& why) {
  ++rejected_;
  const std::lock_guard lock(mutex_);
  last_rejection_ = channel + ": " + why;
}

void LcmBus::Refuse(const std::string& channel, int bytes) {
  ++refused_;
  const std::lock_guard lock(mutex_);
  last_rejection_ = channel + ": " + std::to_string(bytes) +
                    " bytes refused on the rig network (more than one datagram, " +
                    std::to_string(MaxRigMessageBytes(channel)) +
                    " bytes; route the channel to the local network, docs/rig.md)";
}

std::string LcmBus::LastRejection() const {
  const std::lock_guard lock(mutex_);
  return last_rejection_;
}

std::string ResolveLcmUrl(const std::string& url) {
  if (!url.empty()) return url;
  const char* environment = std::getenv("LCM_DEFAULT_URL");
  return environment != nullptr && *environment != 0 ? environment
                                                     : "udpm://239.255.76.67:7667?ttl=0";
}

int64_t NowUtime() { return HostUtime(); }

}  // namespace shapesense
