#include "runtime/lcm/wire_check.h"

#include <algorithm>
#include <vector>

namespace shapesense {
namespace {

// Sizes on the wire (LCM encodes big-endian, booleans as one byte).
constexpr size_t kHash = 8;
constexpr size_t kMacBytes = 32;   // auth_t.mac
constexpr size_t kStageTail = 16;  // stage_time_t after its name: duration_us, end_utime
// width, height, row_stride, pixel_format, compression, exposure_us, gain_db,
// trigger_seq, trigger_utime, frame_id, device_timestamp_ns, host_utime
constexpr size_t kImageFixed = 4 + 4 + 4 + 1 + 1 + 4 + 4 + 8 + 8 + 8 + 8 + 8;
constexpr size_t kVoxelFixed = 8 + 8 + 3 * 8 + 8 + 3 * 4;     // trigger_seq ... dims
constexpr size_t kShapeTail = 3 * 8 + 8 + 1 + 4 * 8 + 8 + 8;  // tip ... configuration_residual_mm
constexpr size_t kCommandTail = 8 + 1 + 4;      // source_trigger_seq, mode, gate_reasons
constexpr size_t kTendonStateEach = 8 + 8 + 4;  // displacement_mm, tension_n, fault

// Walks a buffer, failing as soon as a length does not fit.
class WireWalker {
 public:
  WireWalker(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  bool Skip(size_t bytes) {
    if (bytes > size_ - pos_) return false;
    pos_ += bytes;
    return true;
  }
  // A count or length: a non-negative int32.
  bool Count(int64_t* count) {
    if (4 > size_ - pos_) return false;
    const uint8_t* p = data_ + pos_;
    const uint32_t raw =
        (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
    pos_ += 4;
    *count = static_cast<int32_t>(raw);
    return *count >= 0;
  }
  // An array of `count` elements of `element_bytes` each.
  bool SkipArray(int64_t count, size_t element_bytes) {
    const size_t left = size_ - pos_;
    if (element_bytes > 0 && static_cast<size_t>(count) > left / element_bytes) return false;
    pos_ += static_cast<size_t>(count) * element_bytes;
    return true;
  }
  // LCM strings carry their length including the terminating zero, so at least 1.
  bool SkipString() {
    int64_t length = 0;
    return Count(&length) && length >= 1 && Skip(static_cast<size_t>(length));
  }
  // The type's hash, then header_t: seq, utime, host, data_age_us, and its
  // auth_t: key_id, sender, counter, mac.
  bool HashAndHeader() {
    return Skip(kHash + 8 + 8) && SkipString() && Skip(8 + 4) && SkipString() &&
           Skip(8 + kMacBytes);
  }
  bool StageTimes() {
    int64_t count = 0;
    if (!Count(&count)) return false;
    for (int64_t i = 0; i < count; ++i) {
      if (!SkipString() || !Skip(kStageTail)) return false;
    }
    return true;
  }
  // Three parallel int16 arrays of runs (row, begin, end).
  bool Runs() {
    int64_t count = 0;
    constexpr size_t kRunBytes = 3 * sizeof(int16_t);
    return Count(&count) && SkipArray(count, kRunBytes);
  }
  bool AtEnd() const { return pos_ == size_; }
  size_t position() const { return pos_; }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

}  // namespace

int64_t WireFingerprint(const uint8_t* data, size_t size) {
  if (size < kHash) return 0;
  uint64_t hash = 0;
  for (size_t i = 0; i < kHash; ++i) hash = (hash << 8) | data[i];
  return static_cast<int64_t>(hash);
}

namespace {

// Where an image's pixel count lies (its pixels follow, to the end of the
// buffer), or 0 when the buffer is not a plausible image_t.
size_t ImagePixelCountAt(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  if (!walk.HashAndHeader() || !walk.SkipString() || !walk.Skip(kImageFixed) ||
      !walk.StageTimes()) {
    return 0;
  }
  const size_t count_at = walk.position();
  int64_t bytes = 0;
  return walk.Count(&bytes) && walk.SkipArray(bytes, 1) && walk.AtEnd() ? count_at : 0;
}

}  // namespace

bool WireCheck<image_t>::Plausible(const uint8_t* data, size_t size) {
  return ImagePixelCountAt(data, size) > 0;
}

std::string DecodeImageFields(const void* data, size_t size, image_t* fields,
                              std::span<const uint8_t>* pixels) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (WireFingerprint(bytes, size) != image_t::getHash()) return "not a valid image_t: wrong type";
  const size_t count_at = size > static_cast<size_t>(INT_MAX) ? 0 : ImagePixelCountAt(bytes, size);
  if (count_at == 0) return "not a valid image_t: lengths do not fit";
  const size_t count = size - count_at - 4;  // the pixels run to the end
  // Everything before the pixels, with a pixel count of 0, decodes as an
  // image without pixels: a few hundred bytes copied instead of the image.
  std::vector<uint8_t> head(bytes, bytes + count_at + 4);
  std::fill(head.end() - 4, head.end(), uint8_t{0});
  std::string why = DecodeMessage(head.data(), head.size(), fields);
  if (!why.empty()) return why;
  fields->size = static_cast<int32_t>(count);
  *pixels = {bytes + count_at + 4, count};
  return {};
}

bool WireCheck<voxel_cloud_t>::Plausible(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  int64_t voxels = 0;
  return walk.HashAndHeader() && walk.Skip(kVoxelFixed) && walk.Count(&voxels) &&
         walk.SkipArray(voxels, 4 + 1) && walk.StageTimes() && walk.AtEnd();
}

bool WireCheck<silhouettes_t>::Plausible(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  int64_t views = 0;
  if (!walk.HashAndHeader() || !walk.Skip(8 + 8) || !walk.Count(&views)) return false;
  for (int64_t k = 0; k < views; ++k) {
    int64_t values = 0;
    // camera, width, height, the mask's, the tape's and the band's runs, the band's values
    if (!walk.SkipString() || !walk.Skip(4 + 4) || !walk.Runs() || !walk.Runs() || !walk.Runs() ||
        !walk.Count(&values) || !walk.SkipArray(values, 1)) {
      return false;
    }
  }
  return walk.AtEnd();
}

bool WireCheck<shape_t>::Plausible(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  int64_t points = 0;
  int64_t markers = 0;
  return walk.HashAndHeader() && walk.Skip(8 + 8 + 1) && walk.SkipString() && walk.Count(&points) &&
         walk.SkipArray(points, 3 * 8 + 8 + 8) && walk.Count(&markers) &&
         walk.SkipArray(markers, 3 * 8 + 8 + 8) && walk.Skip(kShapeTail) && walk.StageTimes() &&
         walk.AtEnd();
}

bool WireCheck<tendon_command_t>::Plausible(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  int64_t tendons = 0;
  return walk.HashAndHeader() && walk.Count(&tendons) && walk.SkipArray(tendons, 8) &&
         walk.Skip(kCommandTail) && walk.AtEnd();
}

bool WireCheck<tendon_state_t>::Plausible(const uint8_t* data, size_t size) {
  WireWalker walk(data, size);
  int64_t tendons = 0;
  return walk.HashAndHeader() && walk.Count(&tendons) &&
         walk.SkipArray(tendons, kTendonStateEach) && walk.AtEnd();
}

}  // namespace shapesense
