// The cost of authenticating the messages that move the robot
// (docs/security.md): HMAC-SHA256 signing and verifying (MAC, replay
// window) per message type, on the encoded sizes they have on the wire. A
// sensed shape carries ~400 centreline points (2 mm apart over ~800 mm).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "libs/security/message_auth.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/estop_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense {
namespace {

constexpr size_t kMacOffset = 8;  // any place inside the message: the cost is the bytes

AuthKey BenchKey() {
  AuthKey key;
  key.id = 1;
  key.secret.fill(0x5a);
  return key;
}

template <class Message>
std::vector<uint8_t> Encoded(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

std::vector<uint8_t> ShapeBytes() {
  shape_t shape{};
  shape.num_points = 400;
  shape.centerline.assign(400, std::vector<double>(3, 1.0));
  shape.arc_length.assign(400, 2.0);
  shape.curvature.assign(400, 0.003);
  return Encoded(shape);
}

std::vector<uint8_t> CommandBytes() {
  tendon_command_t command{};
  command.displacement_mm.assign(4, 0.7);
  command.num_tendons = 4;
  return Encoded(command);
}

std::vector<uint8_t> MessageBytes(int64_t type) {
  switch (type) {
    case 0:
      return Encoded(configuration_target_t{});
    case 1:
      return Encoded(estop_t{});
    case 2:
      return CommandBytes();
    default:
      return ShapeBytes();
  }
}

const char* TypeName(int64_t type) {
  static const char* names[] = {"configuration_target_t", "estop_t", "tendon_command_t",
                                "shape_t (400 points)"};
  return names[type];
}

void BM_Sign(benchmark::State& state) {
  std::vector<uint8_t> bytes = MessageBytes(state.range(0));
  MessageSigner signer(KeyRing({BenchKey()}), "control/controller", 1);
  for (auto _ : state) {
    const AuthTag tag = signer.Next();
    benchmark::DoNotOptimize(signer.Sign("SHAPESENSE_TARGET", tag, bytes, kMacOffset));
  }
  state.SetLabel(std::string(TypeName(state.range(0))) + ", " + std::to_string(bytes.size()) +
                 " bytes");
}

void BM_Verify(benchmark::State& state) {
  std::vector<uint8_t> bytes = MessageBytes(state.range(0));
  MessageSigner signer(KeyRing({BenchKey()}), "control/controller", 1);
  MessageVerifier verifier(KeyRing({BenchKey()}));
  for (auto _ : state) {
    state.PauseTiming();
    const AuthTag tag = signer.Next();
    const Mac mac = signer.Sign("SHAPESENSE_TARGET", tag, bytes, kMacOffset);
    std::copy(mac.begin(), mac.end(), bytes.begin() + kMacOffset);
    state.ResumeTiming();
    benchmark::DoNotOptimize(verifier.Verify("SHAPESENSE_TARGET", tag, bytes, kMacOffset));
  }
  state.SetLabel(std::string(TypeName(state.range(0))) + ", " + std::to_string(bytes.size()) +
                 " bytes");
}

BENCHMARK(BM_Sign)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Verify)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace shapesense

BENCHMARK_MAIN();
