#include "clients/tools/attack/attacker.h"

#include <algorithm>
#include <stdexcept>

#include "libs/security/auth_key.h"
#include "runtime/lcm/bus_auth.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/wire_check.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense {
namespace {

// What it keeps of the real traffic per channel: enough for a replay a
// second or two old at 30 Hz.
constexpr size_t kKeptPerChannel = 90;
constexpr int64_t kOldReplayUs = 1'000'000;

const std::vector<std::string>& ListenedChannels() {
  static const std::vector<std::string> listened = {channels::kShape, channels::kTarget,
                                                    channels::kPlantCommand};
  return listened;
}

configuration_target_t ForgedTarget(int64_t now) {
  configuration_target_t target{};
  target.header.utime = now;
  target.kind = configuration_target_t::KIND_CONFIGURATION;
  target.q[0] = 0.02;  // a hard bend the experiment never asks for
  target.q[1] = -0.02;
  target.q[3] = 0.02;
  target.source = kAttackerSource;
  return target;
}

shape_t ForgedShape(int64_t now, int64_t round) {
  shape_t shape{};
  shape.header.utime = now;
  shape.trigger_seq = kForgedTrigger + round;
  shape.trigger_utime = now;
  shape.valid = true;
  shape.has_configuration = true;
  shape.q[0] = -0.02;  // "the tip is far off": the loop would pull the other way
  shape.q[3] = 0.01;
  return shape;
}

tendon_command_t ForgedCommand(int64_t now) {
  tendon_command_t command{};
  command.header.utime = now;
  command.num_tendons = 4;
  command.displacement_mm = {6.0, 0.0, 6.0, 0.0};
  command.source_trigger_seq = kForgedTrigger;
  command.mode = tendon_command_t::MODE_OPEN_LOOP;
  return command;
}

}  // namespace

Attacker::Attacker(AttackOptions options)
    : options_(std::move(options)), lcm_(ResolveLcmUrl(options_.lcm_url)), random_(options_.seed) {
  if (!lcm_.good()) throw std::runtime_error("attack: LCM could not start on " + options_.lcm_url);
  for (const std::string& channel : ListenedChannels()) {
    lcm_.subscribeFunction(options_.prefix + channel, &Attacker::OnMessage, this);
  }
}

void Attacker::OnMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                         Attacker* self) {
  const auto* data = static_cast<const uint8_t*>(buffer->data);
  std::deque<Heard>& kept = self->heard_[channel.substr(self->options_.prefix.size())];
  kept.push_back({buffer->recv_utime, std::vector<uint8_t>(data, data + buffer->data_size)});
  if (kept.size() > kKeptPerChannel) kept.pop_front();
}

void Attacker::Run(const std::atomic<bool>& stop) {
  const int64_t period_us = static_cast<int64_t>(1e6 / options_.rate_hz);
  const int64_t start = NowUtime();
  const int64_t end =
      options_.duration_s > 0 ? start + static_cast<int64_t>(options_.duration_s * 1e6) : INT64_MAX;
  int64_t next = start + period_us;
  while (!stop.load()) {
    const int64_t now = NowUtime();
    if (now >= end) break;
    if (now >= next) {
      AttackOnce(now);
      next += period_us;
      continue;
    }
    lcm_.handleTimeout(static_cast<int>(std::max<int64_t>(1, (next - now) / 1000)));
  }
}

std::vector<uint8_t> Attacker::Recorded(const std::string& channel, int64_t age_us,
                                        int64_t now) const {
  const auto found = heard_.find(channel);
  if (found == heard_.end() || found->second.empty()) return {};
  const std::deque<Heard>& kept = found->second;
  // The newest at least `age_us` old (the oldest kept when none is).
  const auto old_enough = std::find_if(kept.rbegin(), kept.rend(), [&](const Heard& heard) {
    return now - heard.receive_utime >= age_us;
  });
  return old_enough != kept.rend() ? old_enough->bytes : kept.front().bytes;
}

// One message per round, the kinds in turn.
void Attacker::AttackOnce(int64_t now) {
  const int64_t round = round_++;
  std::uniform_int_distribution<int> byte(0, 255);
  // A key of its own, and a made-up MAC under a real sender's key id.
  static const KeyRing foreign({AuthKey{0xBADu, {}}});
  MessageSigner impostor(foreign, "camera/shapesense-shape", static_cast<uint64_t>(now));
  const auto borrow_identity = [&](auto message, const std::string& from_channel) {
    message.header.auth.sender = "control/shapesense-controller";
    message.header.auth.counter = now;
    shape_t real;
    const std::vector<uint8_t> recorded = Recorded(from_channel, 0, now);
    if (!recorded.empty() && DecodeMessage(recorded.data(), recorded.size(), &real).empty()) {
      message.header.auth = real.header.auth;
      message.header.auth.counter += 1000;
    }
    for (uint8_t& b : message.header.auth.mac) b = static_cast<uint8_t>(byte(random_));
    return EncodeMessage(message);
  };
  const std::string shape = channels::kShape;
  const std::string target = channels::kTarget;
  const std::string plant = channels::kPlantCommand;
  switch (round % 10) {
    case 0:
      return Send("unsigned_target", target, EncodeMessage(ForgedTarget(now)));
    case 1:
      return Send("foreign_key_shape", shape,
                  EncodeSigned(ForgedShape(now, round), impostor, options_.prefix + shape, 0));
    case 2:
      return Send("forged_mac_plant_command", plant, borrow_identity(ForgedCommand(now), shape));
    case 3:
      return Send("replayed_shape", shape, Recorded(shape, 0, now));
    case 4:
      return Send("unsigned_shape", shape, EncodeMessage(ForgedShape(now, round)));
    case 5:
      return Send("forged_mac_target", target, borrow_identity(ForgedTarget(now), shape));
    case 6:
      return Send("replayed_old_plant_command", plant, Recorded(plant, kOldReplayUs, now));
    case 7: {
      std::vector<uint8_t> flipped = Recorded(shape, 0, now);
      if (!flipped.empty()) flipped[flipped.size() / 2] ^= 0x10;
      return Send("flipped_shape", shape, flipped);
    }
    case 8:
      return Send("replayed_target", target, Recorded(target, 0, now));
    default:
      return Send("foreign_key_plant_command", plant,
                  EncodeSigned(ForgedCommand(now), impostor, options_.prefix + plant, 0));
  }
}

void Attacker::Send(const std::string& kind, const std::string& channel,
                    const std::vector<uint8_t>& bytes) {
  if (bytes.empty()) return;  // nothing of that channel heard yet
  lcm_.publish(options_.prefix + channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  const std::lock_guard lock(mutex_);
  ++sent_[kind];
}

std::map<std::string, int64_t> Attacker::sent() const {
  const std::lock_guard lock(mutex_);
  return sent_;
}

}  // namespace shapesense
