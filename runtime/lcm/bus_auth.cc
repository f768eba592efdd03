#include "runtime/lcm/bus_auth.h"

#include <cerrno>  // program_invocation_short_name
#include <sstream>
#include <stdexcept>

#include "runtime/host_clock.h"
#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

// An attacker names itself: keep what reaches a log short and printable.
std::string Printable(const std::string& text) {
  constexpr size_t kMax = 64;
  std::string shown;
  for (const char c : text.substr(0, kMax)) shown += (c >= 0x20 && c < 0x7f) ? c : '?';
  return text.size() > kMax ? shown + "..." : shown;
}

std::string ModeOn(const KeyRing& keys) {
  std::string mode = "on (key";
  const std::vector<uint32_t> ids = keys.ids();
  mode += ids.size() > 1 ? "s " : " ";
  for (size_t i = 0; i < ids.size(); ++i) {
    if (i > 0) mode += ", ";
    mode += std::to_string(ids[i]);
  }
  return mode + ")";
}

}  // namespace

bool IsSignedChannel(const std::string& channel) {
  return channel == channels::kTarget || channel == channels::kEstop ||
         channel == channels::kTendonCommand || channel == channels::kPlantCommand ||
         channel == channels::kPlantState || channel == channels::kShape;
}

AuthTag TagOf(const auth_t& auth) {
  return {static_cast<uint32_t>(auth.key_id), auth.sender, static_cast<uint64_t>(auth.counter)};
}

std::string FormatKeyFiles(const std::vector<std::filesystem::path>& files) {
  std::string value;
  for (const std::filesystem::path& file : files) {
    if (!value.empty()) value += ':';
    value += file.string();
  }
  return value;
}

std::vector<std::filesystem::path> ParseKeyFiles(const std::string& value) {
  std::vector<std::filesystem::path> files;
  std::stringstream stream(value);
  for (std::string file; std::getline(stream, file, ':');) {
    if (!file.empty()) files.emplace_back(file);
  }
  return files;
}

BusAuth::BusAuth(std::optional<KeyRing> keys, std::string sender, FirstContactRule first_contact,
                 std::string off_mode)
    : off_mode_(std::move(off_mode)) {
  if (!keys) return;
  if (first_contact.receiver_start_utime == 0) first_contact.receiver_start_utime = HostUtime();
  signer_.emplace(*keys, std::move(sender), CounterFloor());
  keys_ = std::move(keys);
  first_contact_ = first_contact;
}

std::string BusAuth::Verify(int subscription, const std::string& wire_channel,
                            std::span<const uint8_t> bytes, const auth_t& auth, size_t mac_offset,
                            int64_t now_utime) {
  const AuthTag tag = TagOf(auth);
  std::optional<AuthRejection> rejection;
  {
    const std::lock_guard lock(verify_mutex_);
    auto verifier = verifiers_.find(subscription);
    if (verifier == verifiers_.end()) {
      verifier = verifiers_.try_emplace(subscription, *keys_, first_contact_).first;
    }
    rejection = verifier->second.Verify(wire_channel, tag, bytes, mac_offset, now_utime);
  }
  if (!rejection) return {};
  std::string why = std::string("not authentic (") + AuthRejectionName(*rejection) + ")";
  if (*rejection != AuthRejection::kUnsigned) {
    why += ": sender '" + Printable(tag.sender) + "', key " + std::to_string(tag.key_id) +
           ", counter " + std::to_string(tag.counter);
  }
  return why;
}

void BusAuth::CountUnsignedEstop() {
  const std::lock_guard lock(verify_mutex_);
  ++estops_accepted_unsigned_;
}

AuthCounts BusAuth::Counts() const {
  AuthCounts counts;
  if (!on()) {
    counts.mode = off_mode_;
    return counts;
  }
  counts.mode = ModeOn(signer_->keys());
  const std::lock_guard lock(verify_mutex_);
  for (const auto& [subscription, verifier] : verifiers_) {
    counts.accepted += verifier.accepted();
    for (const auto& [reason, count] : verifier.rejections()) counts.rejections[reason] += count;
  }
  counts.estops_accepted_unsigned = estops_accepted_unsigned_;
  return counts;
}

uint64_t BusAuth::CounterFloor() { return static_cast<uint64_t>(HostUtime()); }

std::string DefaultSender(const std::string& host, int index) {
  std::string sender = host + "/" + program_invocation_short_name;
  return index == 0 ? sender : sender + "#" + std::to_string(index);
}

}  // namespace shapesense
