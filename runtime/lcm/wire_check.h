#pragma once

// A look at a raw LCM buffer before lcm-gen's decoder reads it. The generated
// decoders size every variable-length array from the count in the buffer
// before checking that the buffer holds that many elements, so a corrupted
// count (a flipped bit, a hostile sender) makes them allocate and zero up to
// ~100 GB, or throw from inside an LCM callback. The check walks the wire
// layout of the types with arrays and accepts a buffer only when every count
// and string length fits in the bytes that follow and the message ends
// exactly at the buffer's end; only then is it decoded.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <span>
#include <string>
#include <vector>

#include "shapesense/image_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/silhouettes_t.hpp"
#include "shapesense/tendon_command_t.hpp"
#include "shapesense/tendon_state_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {

// Types without variable-length arrays cannot over-allocate: any buffer may
// be handed to their decoder (their strings are checked by lcm-gen's code).
template <class Message>
struct WireCheck {
  static bool Plausible(const uint8_t*, size_t) { return true; }
};

// Keep these walkers in step with messages/*.lcm (wire_check_test encodes
// random messages of each type and checks that they pass).
template <>
struct WireCheck<image_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};
template <>
struct WireCheck<voxel_cloud_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};
template <>
struct WireCheck<silhouettes_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};
template <>
struct WireCheck<shape_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};
template <>
struct WireCheck<tendon_command_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};
template <>
struct WireCheck<tendon_state_t> {
  static bool Plausible(const uint8_t* data, size_t size);
};

// The type fingerprint at the start of an encoded buffer (0 when shorter than 8 bytes).
int64_t WireFingerprint(const uint8_t* data, size_t size);

// `message` as it travels (the inverse of DecodeMessage).
template <class Message>
std::vector<uint8_t> EncodeMessage(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Decodes `size` bytes into `out`; "" on success, otherwise why the buffer is
// not a valid message ("not a valid image_t: ..."). Never throws.
template <class Message>
std::string DecodeMessage(const void* data, size_t size, Message* out) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  const std::string invalid = "not a valid " + std::string(Message::getTypeName());
  if (size > static_cast<size_t>(INT_MAX)) return invalid + ": too large";
  if (WireFingerprint(bytes, size) != Message::getHash()) return invalid + ": wrong type";
  if (!WireCheck<Message>::Plausible(bytes, size)) return invalid + ": lengths do not fit";
  try {
    if (out->decode(data, 0, static_cast<int>(size)) < 0) return invalid + ": truncated";
  } catch (const std::exception& e) {
    return invalid + ": " + e.what();
  }
  return {};
}

// An image's fields decoded, its pixel bytes left where they are: `pixels`
// views them at the end of `data` (image_t's bytes are its last field),
// `fields->data` stays empty and `fields->size` counts them. For a service
// that reads an image once, inside its LCM callback: the ~1 MB of a VGA
// image is neither zeroed nor copied. "" on success, otherwise why the
// buffer is not a valid image_t. Never throws.
std::string DecodeImageFields(const void* data, size_t size, image_t* fields,
                              std::span<const uint8_t>* pixels);

}  // namespace shapesense
