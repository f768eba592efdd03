// The generated LCM types round-trip through their wire encoding, and a
// truncated or corrupted buffer is rejected rather than read.
#include <gtest/gtest.h>

#include <vector>

#include "shapesense/image_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {
namespace {

template <class T>
std::vector<uint8_t> Encode(const T& message) {
  std::vector<uint8_t> buffer(static_cast<size_t>(message.getEncodedSize()));
  EXPECT_EQ(message.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  return buffer;
}

shape_t MakeShape() {
  shape_t shape{};
  shape.header.seq = 7;
  shape.header.utime = 1'700'000'000'000'000;
  shape.trigger_seq = 42;
  shape.valid = true;
  shape.num_points = 3;
  shape.centerline = {{0, 0, 0}, {0, 0, 1.5}, {0, 0.1, 3}};
  shape.arc_length = {0, 1.5, 3.0};
  shape.curvature = {0.0, 0.01, 0.02};
  shape.num_markers = 1;
  shape.markers = {{0, 0, 1.5}};
  shape.marker_arc_length = {1.5};
  shape.marker_std_mm = {0.04};
  shape.q[0] = 0.01;
  shape.num_stage_times = 1;
  shape.stage_times.push_back({"carving", 250, 1'700'000'000'000'250});
  return shape;
}

TEST(MessagesTest, ShapeRoundTripsThroughItsEncoding) {
  const shape_t shape = MakeShape();
  const std::vector<uint8_t> buffer = Encode(shape);
  shape_t decoded;
  ASSERT_EQ(decoded.decode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  EXPECT_EQ(decoded.header.seq, 7);
  EXPECT_EQ(decoded.centerline, shape.centerline);
  EXPECT_EQ(decoded.marker_arc_length, shape.marker_arc_length);
  EXPECT_EQ(decoded.marker_std_mm, shape.marker_std_mm);
  ASSERT_EQ(decoded.stage_times.size(), 1u);
  EXPECT_EQ(decoded.stage_times[0].stage, "carving");
  EXPECT_EQ(decoded.stage_times[0].duration_us, 250);
}

TEST(MessagesTest, TruncatedBufferIsRejected) {
  const std::vector<uint8_t> buffer = Encode(MakeShape());
  shape_t decoded;
  for (size_t cut : {buffer.size() - 1, buffer.size() / 2, size_t{8}, size_t{0}}) {
    EXPECT_LT(decoded.decode(buffer.data(), 0, static_cast<int>(cut)), 0) << "cut at " << cut;
  }
}

TEST(MessagesTest, WrongTypeFingerprintIsRejected) {
  const std::vector<uint8_t> buffer = Encode(MakeShape());
  voxel_cloud_t voxels;
  EXPECT_LT(voxels.decode(buffer.data(), 0, static_cast<int>(buffer.size())), 0);
}

TEST(MessagesTest, ImageCarriesItsPixelsAndTimes) {
  image_t image{};
  image.camera = "cam0";
  image.width = 4;
  image.height = 2;
  image.row_stride = 12;
  image.pixel_format = image_t::PIXEL_BGR8;
  image.trigger_seq = 3;
  image.size = 24;
  image.data.assign(24, 0x5a);
  const std::vector<uint8_t> buffer = Encode(image);
  image_t decoded;
  ASSERT_GT(decoded.decode(buffer.data(), 0, static_cast<int>(buffer.size())), 0);
  EXPECT_EQ(decoded.data, image.data);
  EXPECT_EQ(int{decoded.pixel_format}, int{image_t::PIXEL_BGR8});
}

}  // namespace
}  // namespace shapesense
