#pragma once

// A hostile process on the rig network, for the security tests and
// `shapesense demo --attacker` (docs/security.md): it holds no rig key,
// listens to the real traffic, and publishes in turn forged targets, shapes
// and plant commands (unsigned, signed with a key of its own, or carrying a
// real sender's key id and counter with a made-up MAC), real messages with
// a bit flipped, and replays of real ones, at once and a second later. Its
// forgeries carry markers (kForgedTrigger, source "attacker") by which a
// receiver that acted on one would show it.
#include <atomic>
#include <cstdint>
#include <deque>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <vector>

namespace shapesense {

// Trigger sequence of forged shapes and source_trigger_seq of forged plant
// commands: far above any real frame-set's.
inline constexpr int64_t kForgedTrigger = 1'000'000'000;
inline constexpr const char* kAttackerSource = "attacker";

struct AttackOptions {
  std::string lcm_url;  // the rig network
  std::string prefix;   // the rig's channel prefix
  double rate_hz = 30.0;
  double duration_s = 0.0;  // 0: until stopped
  uint32_t seed = 1;
};

class Attacker {
 public:
  // Throws std::runtime_error when LCM cannot start on the URL.
  explicit Attacker(AttackOptions options);

  // Listens and attacks until `stop` or the duration.
  void Run(const std::atomic<bool>& stop);
  // Messages sent, by kind ("unsigned_target", "replayed_shape", ...).
  std::map<std::string, int64_t> sent() const;

 private:
  struct Heard {
    int64_t receive_utime = 0;
    std::vector<uint8_t> bytes;
  };
  static void OnMessage(const lcm::ReceiveBuffer* buffer, const std::string& channel,
                        Attacker* self);
  void AttackOnce(int64_t now);
  void Send(const std::string& kind, const std::string& channel, const std::vector<uint8_t>& bytes);
  // The newest real message on `channel`, or one at least `age_us` old;
  // empty when none.
  std::vector<uint8_t> Recorded(const std::string& channel, int64_t age_us, int64_t now) const;

  AttackOptions options_;
  lcm::LCM lcm_;
  std::mt19937 random_;
  std::map<std::string, std::deque<Heard>> heard_;  // by channel (without the prefix)
  std::map<std::string, int64_t> sent_;
  int64_t round_ = 0;
  mutable std::mutex mutex_;
};

}  // namespace shapesense
