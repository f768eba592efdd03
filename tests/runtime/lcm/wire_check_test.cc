// The look at raw buffers before lcm-gen's decoders: every honest encoding
// passes; a truncated one, one with trailing bytes, and any corrupted count
// that does not fit the buffer are refused, so a decoder never sizes an
// array from a count larger than the buffer (which could ask for ~100 GB).
#include "runtime/lcm/wire_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <span>

#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/silhouette_message.h"
#include "runtime/lcm/stage_times.h"
#include "shapesense/service_status_t.hpp"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

using testing::Encode;

std::vector<stage_time_t> RandomStages(std::mt19937& rng) {
  std::vector<stage_time_t> stages;
  for (unsigned i = rng() % 4; i > 0; --i) {
    stages.push_back(MakeStageTime(std::string(1 + rng() % 12, 'a'), rng() % 1000, rng()));
  }
  return stages;
}

image_t RandomImage(std::mt19937& rng) {
  cv::Mat pixels(1 + static_cast<int>(rng() % 9), 1 + static_cast<int>(rng() % 9), CV_8UC3,
                 cv::Scalar(static_cast<double>(rng() % 256), 7, 9));
  image_t image = ImageToMessage(pixels, image_t::PIXEL_BGR8);
  image.camera = std::string(rng() % 6, 'c');
  image.stage_times = RandomStages(rng);
  image.num_stage_times = static_cast<int32_t>(image.stage_times.size());
  return image;
}

voxel_cloud_t RandomVoxels(std::mt19937& rng) {
  voxel_cloud_t voxels{};
  voxels.num_voxels = static_cast<int32_t>(rng() % 20);
  voxels.voxels.assign(static_cast<size_t>(voxels.num_voxels), 3);
  voxels.labels.assign(static_cast<size_t>(voxels.num_voxels), 1);
  voxels.stage_times = RandomStages(rng);
  voxels.num_stage_times = static_cast<int32_t>(voxels.stage_times.size());
  return voxels;
}

shape_t RandomShape(std::mt19937& rng) {
  ShapeEstimate estimate;
  estimate.error = std::string(rng() % 8, 'e');
  for (unsigned i = rng() % 10; i > 0; --i) estimate.centerline.push_back(Vec3(1, 2, 3));
  for (unsigned i = rng() % 3; i > 0; --i) estimate.markers.push_back(Vec3(4, 5, 6));
  shape_t shape = ShapeToMessage(estimate);
  shape.stage_times = RandomStages(rng);
  shape.num_stage_times = static_cast<int32_t>(shape.stage_times.size());
  return shape;
}

silhouettes_t RandomSilhouettes(std::mt19937& rng) {
  Rig rig;
  SilhouetteSet set;
  set.views.resize(rng() % 4);
  for (CompactSilhouette& view : set.views) {
    rig.cameras.emplace_back();
    rig.cameras.back().name = std::string(1 + rng() % 5, 'c');
    view.width = 40;
    view.height = 30;
    for (int y = 0; y < static_cast<int>(rng() % 6); ++y) view.mask.push_back({y, 3, 9});
    for (int y = 0; y < static_cast<int>(rng() % 3); ++y) view.markers.push_back({y, 4, 5});
    for (int y = 0; y < static_cast<int>(rng() % 6); ++y) view.band.push_back({y, 1, 4});
    view.band_difference.assign(3 * view.band.size(), 7);
  }
  silhouettes_t message{};
  SilhouettesToMessage(rig, set, &message);
  return message;
}

// Every honest encoding passes and decodes; cutting or extending it fails;
// random corruption never makes a decode throw, and a buffer the check
// passes decodes into arrays no larger than the buffer.
template <class Message, class Make, class Largest>
void CheckType(Make make, Largest largest) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<uint8_t> bytes = Encode(make(rng));
    Message decoded;
    EXPECT_TRUE(WireCheck<Message>::Plausible(bytes.data(), bytes.size()));
    EXPECT_EQ(DecodeMessage(bytes.data(), bytes.size(), &decoded), "");
    for (size_t cut : {size_t{1}, size_t{4}, bytes.size() / 2}) {
      if (cut >= bytes.size()) continue;
      EXPECT_FALSE(WireCheck<Message>::Plausible(bytes.data(), bytes.size() - cut));
      EXPECT_NE(DecodeMessage(bytes.data(), bytes.size() - cut, &decoded), "");
    }
    bytes.push_back(0);
    EXPECT_FALSE(WireCheck<Message>::Plausible(bytes.data(), bytes.size()));
    bytes.pop_back();
    for (int corruption = 0; corruption < 50; ++corruption) {
      std::vector<uint8_t> broken = bytes;
      for (int flips = 1 + static_cast<int>(rng() % 4); flips > 0; --flips) {
        broken[8 + rng() % (broken.size() - 8)] = static_cast<uint8_t>(rng() % 2 ? 0xFF : rng());
      }
      Message out;
      if (DecodeMessage(broken.data(), broken.size(), &out).empty()) {
        EXPECT_LE(largest(out), broken.size());
      }
    }
  }
}

TEST(WireCheckTest, ImageMessages) {
  CheckType<image_t>(
      RandomImage, [](const image_t& m) { return std::max(m.data.size(), m.stage_times.size()); });
}

TEST(WireCheckTest, VoxelCloudMessages) {
  CheckType<voxel_cloud_t>(RandomVoxels, [](const voxel_cloud_t& m) {
    return std::max(m.voxels.size(), m.stage_times.size());
  });
}

TEST(WireCheckTest, ShapeMessages) {
  CheckType<shape_t>(RandomShape, [](const shape_t& m) {
    return std::max({m.centerline.size(), m.markers.size(), m.stage_times.size()});
  });
}

TEST(WireCheckTest, SilhouetteMessages) {
  CheckType<silhouettes_t>(RandomSilhouettes, [](const silhouettes_t& m) {
    size_t largest = m.views.size();
    for (const silhouette_view_t& v : m.views) {
      largest = std::max({largest, v.mask_row.size(), v.tape_row.size(), v.band_row.size(),
                          v.band_difference.size()});
    }
    return largest;
  });
}

// An image's fields decoded in place equal lcm-gen's full decode, and its
// bytes are viewed where they lie: the very bytes sent, none copied.
TEST(WireCheckTest, ImageFieldsDecodeInPlaceAsTheFullDecode) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 40; ++trial) {
    image_t sent = RandomImage(rng);
    sent.trigger_seq = static_cast<int64_t>(rng());
    sent.frame_id = static_cast<int64_t>(rng());
    sent.device_timestamp_ns = static_cast<int64_t>(rng()) << 20;
    const std::vector<uint8_t> bytes = Encode(sent);
    image_t fields;
    std::span<const uint8_t> pixels;
    ASSERT_EQ(DecodeImageFields(bytes.data(), bytes.size(), &fields, &pixels), "");
    EXPECT_TRUE(fields.data.empty());
    EXPECT_EQ(fields.size, sent.size);
    ASSERT_EQ(pixels.size(), sent.data.size());
    EXPECT_EQ(pixels.data(), bytes.data() + bytes.size() - sent.data.size());
    EXPECT_TRUE(std::equal(pixels.begin(), pixels.end(), sent.data.begin()));
    fields.data.assign(pixels.begin(), pixels.end());
    EXPECT_EQ(Encode(fields), bytes) << "every field as the full decode gives it";
  }
}

TEST(WireCheckTest, ImageFieldsRefuseWhatTheFullDecodeRefuses) {
  std::mt19937 rng(14);
  const std::vector<uint8_t> bytes = Encode(RandomImage(rng));
  image_t fields;
  std::span<const uint8_t> pixels;
  for (size_t cut : {size_t{1}, size_t{4}, bytes.size() / 2}) {
    EXPECT_NE(DecodeImageFields(bytes.data(), bytes.size() - cut, &fields, &pixels), "");
  }
  const std::vector<uint8_t> voxels = Encode(voxel_cloud_t{});
  EXPECT_NE(DecodeImageFields(voxels.data(), voxels.size(), &fields, &pixels).find("wrong type"),
            std::string::npos);
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_NE(DecodeImageFields(longer.data(), longer.size(), &fields, &pixels), "");
}

TEST(WireCheckTest, AHugeCountIsRefusedBeforeAnyAllocation) {
  std::mt19937 rng(12);
  image_t image = RandomImage(rng);
  image.stage_times.clear();
  image.num_stage_times = 0;
  std::vector<uint8_t> bytes = Encode(image);
  // num_stage_times sits 4 bytes before the pixel count, which precedes the pixels.
  const size_t stage_count = bytes.size() - image.data.size() - 8;
  for (const uint32_t count : {0x7FFFFFFFu, 0x10000000u, 0xFFFFFFFFu}) {
    for (int b = 0; b < 4; ++b)
      bytes[stage_count + static_cast<size_t>(b)] = static_cast<uint8_t>(count >> (24 - 8 * b));
    image_t out;
    const std::string reason = DecodeMessage(bytes.data(), bytes.size(), &out);
    EXPECT_NE(reason.find("not a valid image_t"), std::string::npos) << reason;
  }
}

TEST(WireCheckTest, WrongTypesAndGarbageAreRefused) {
  image_t image;
  const std::vector<uint8_t> voxels = Encode(voxel_cloud_t{});
  EXPECT_NE(DecodeMessage(voxels.data(), voxels.size(), &image).find("wrong type"),
            std::string::npos);
  const std::vector<uint8_t> garbage(100, 0xAB);
  EXPECT_NE(DecodeMessage(garbage.data(), garbage.size(), &image), "");
  EXPECT_NE(DecodeMessage(garbage.data(), 3, &image), "");
  // A type without arrays needs no walker; its decoder still never throws out.
  service_status_t status{};
  status.service = "carving";
  std::vector<uint8_t> bytes = Encode(status);
  EXPECT_EQ(DecodeMessage(bytes.data(), bytes.size(), &status), "");
  // After the hash and the header (with its auth):
  bytes[8 + static_cast<size_t>(status.header._getEncodedSizeNoHash())] =
      0xFF;  // the service name's length: negative
  EXPECT_NE(DecodeMessage(bytes.data(), bytes.size(), &status), "");
}

}  // namespace
}  // namespace shapesense
