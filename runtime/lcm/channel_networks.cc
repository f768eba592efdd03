#include "runtime/lcm/channel_networks.h"

#include <stdexcept>

#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

// LCM 1.3.1 sends a message in one datagram up to this size, its short
// header (8 bytes) and the channel name (with its NUL) included.
constexpr int kLcmShortMessageMax = 65499;
constexpr int kLcmShortHeader = 8;

std::regex Compile(const std::string& pattern) {
  try {
    return std::regex(pattern);
  } catch (const std::regex_error& error) {
    throw std::invalid_argument("channel pattern '" + pattern + "': " + error.what());
  }
}

Network ParseNetwork(const std::string& name, const std::string& item) {
  if (name == "rig") return Network::kRig;
  if (name == "local") return Network::kLocal;
  throw std::invalid_argument("channel route '" + item + "': expected 'rig' or 'local' after '='");
}

}  // namespace

const char* NetworkName(Network network) { return network == Network::kRig ? "rig" : "local"; }

ChannelNetworks::ChannelNetworks(const std::vector<ChannelRoute>& overrides) {
  for (const ChannelRoute& route : overrides) {
    rules_.emplace_back(Compile(route.pattern), route.network);
    if (route.network == Network::kLocal) local_examples_.push_back(route.pattern);
  }
  local_examples_.push_back(channels::Image("cam0"));
  local_examples_.push_back(channels::Silhouette("cam0"));
  rules_.emplace_back(Compile(channels::kImagePattern), Network::kLocal);
  rules_.emplace_back(Compile(channels::kSilhouettePattern), Network::kLocal);
}

Network ChannelNetworks::Of(const std::string& channel) const {
  for (const auto& [pattern, network] : rules_) {
    if (std::regex_match(channel, pattern)) return network;
  }
  return Network::kRig;
}

bool ChannelNetworks::MayBeLocal(const std::string& pattern) const {
  const std::regex expression = Compile(pattern);
  for (const std::string& example : local_examples_) {
    if (std::regex_match(example, expression)) return true;
  }
  return false;
}

std::vector<ChannelRoute> ChannelNetworks::Parse(const std::string& text) {
  std::vector<ChannelRoute> routes;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find(',', start);
    if (end == std::string::npos) end = text.size();
    const std::string item = text.substr(start, end - start);
    const size_t equals = item.rfind('=');
    if (equals == std::string::npos || equals == 0) {
      throw std::invalid_argument("channel route '" + item + "': expected CHANNEL=rig|local");
    }
    routes.push_back({item.substr(0, equals), ParseNetwork(item.substr(equals + 1), item)});
    Compile(routes.back().pattern);
    start = end + 1;
  }
  return routes;
}

std::string ChannelNetworks::Format(const std::vector<ChannelRoute>& routes) {
  std::string text;
  for (const ChannelRoute& route : routes) {
    if (!text.empty()) text += ',';
    text += route.pattern + "=" + NetworkName(route.network);
  }
  return text;
}

bool IsPlainChannel(const std::string& channel) {
  return channel.find_first_of(".*+?[](){}|^$\\") == std::string::npos;
}

int MaxRigMessageBytes(const std::string& channel) {
  return kLcmShortMessageMax - kLcmShortHeader - static_cast<int>(channel.size()) - 1;
}

bool IsLossTolerant(const std::string& channel) { return channel == channels::kVoxels; }

}  // namespace shapesense
