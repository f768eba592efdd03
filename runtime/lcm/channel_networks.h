#pragma once

// Which LCM network each channel travels on.
//
// Every program has two: the host-local one (ttl=0: nothing leaves the
// host) for images and anything large, and the rig network (ttl=1, the
// rig's own group, routed to the rig's interface: docs/rig.md) for the
// compact messages the hosts share. A ~1 MB image is about 16 LCM fragments
// and 700 Ethernet frames, and Debian's LCM 1.3.1 drops a whole message when
// one fragment is lost or reordered, so images must never cross a network.
#include <regex>
#include <string>
#include <vector>

namespace shapesense {

enum class Network { kRig, kLocal };

const char* NetworkName(Network network);

// One rule: channels that fully match `pattern` (an LCM regular expression,
// without the rig prefix) travel on `network`.
struct ChannelRoute {
  std::string pattern;
  Network network = Network::kRig;
};

class ChannelNetworks {
 public:
  // The rules in `overrides` come first, then the defaults: camera images
  // (SHAPESENSE_IMAGE_<camera>) and the monitoring silhouettes
  // (SHAPESENSE_SILHOUETTE_<camera>, images too) local, everything else on
  // the rig network. Throws std::invalid_argument on a bad pattern.
  explicit ChannelNetworks(const std::vector<ChannelRoute>& overrides = {});

  Network Of(const std::string& channel) const;
  // Whether the regular expression `pattern` matches a channel that travels
  // locally (a camera's images or silhouettes, an override's channel), so
  // that a subscription to it must also listen on the local network.
  bool MayBeLocal(const std::string& pattern) const;

  // Parses "CHANNEL=local,PATTERN=rig,..." (the rig file's and
  // SHAPESENSE_CHANNEL_NETWORKS' form). Throws std::invalid_argument naming
  // the item it cannot read.
  static std::vector<ChannelRoute> Parse(const std::string& text);
  static std::string Format(const std::vector<ChannelRoute>& routes);

 private:
  std::vector<std::pair<std::regex, Network>> rules_;
  std::vector<std::string> local_examples_;  // channels that travel locally
};

// Whether `channel` is a plain name (no regular-expression characters), so
// that it travels on one network; a pattern may match channels of both.
bool IsPlainChannel(const std::string& channel);

// The most a message may take on the rig network without being split into
// fragments: one UDP datagram of LCM's, less its header and the channel
// name. A fragmented message is lost whole when one fragment is, so only a
// message documented as tolerant to loss may be larger (IsLossTolerant).
int MaxRigMessageBytes(const std::string& channel);

// The rig network's channels whose messages may exceed one datagram: losing
// one loses that frame-set, which the receiver counts (the voxel cloud of a
// thick manipulator: about 5 bytes a voxel).
bool IsLossTolerant(const std::string& channel);

}  // namespace shapesense
