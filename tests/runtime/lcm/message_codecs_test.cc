// Conversions between the LCM messages and the libraries' types: round trips
// for every pixel format and compression, and malformed messages (wrong
// sizes, formats, strides, truncated or garbage data) rejected with a reason.
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/stage_times.h"
#include "runtime/lcm/voxel_cloud_message.h"

#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "libs/silhouette/silhouette.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

cv::Mat RandomBgr(std::mt19937& rng, int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  for (cv::Vec3b& pixel : cv::Mat_<cv::Vec3b>(image)) {
    pixel = cv::Vec3b(static_cast<uint8_t>(rng()), static_cast<uint8_t>(rng()),
                      static_cast<uint8_t>(rng()));
  }
  return image;
}

// A smooth image (demosaicing and JPEG are close to exact on it).
cv::Mat SmoothBgr(int width, int height, int phase) {
  cv::Mat image(height, width, CV_8UC3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      image.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>(40 + (x + phase) % 160),
                                            static_cast<uint8_t>(60 + y % 150),
                                            static_cast<uint8_t>(100 + (x + y) / 8 % 100));
    }
  }
  return image;
}

image_t Named(image_t image) {
  image.camera = "cam0";
  return image;
}

double MaxDifference(const cv::Mat& a, const cv::Mat& b) {
  double max = 0.0;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &max);
  return max;
}

TEST(MessageConvertTest, RawBgrRgbAndMonoRoundTripExactly) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const int width = 1 + static_cast<int>(rng() % 97);
    const int height = 1 + static_cast<int>(rng() % 61);
    const cv::Mat bgr = RandomBgr(rng, width, height);
    cv::Mat rgb;
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    cv::Mat grey;
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    cv::Mat out;
    ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(bgr, image_t::PIXEL_BGR8)), &out), "");
    EXPECT_EQ(MaxDifference(out, bgr), 0.0);
    ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(rgb, image_t::PIXEL_RGB8)), &out), "");
    EXPECT_EQ(MaxDifference(out, bgr), 0.0);
    ASSERT_EQ(ImageMessageToMono(Named(ImageToMessage(grey, image_t::PIXEL_MONO8)), &out), "");
    EXPECT_EQ(MaxDifference(out, grey), 0.0);
    ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(grey, image_t::PIXEL_MONO8)), &out), "");
    EXPECT_EQ(out.type(), CV_8UC3);
  }
}

TEST(MessageConvertTest, PngIsLosslessAndJpegClose) {
  std::mt19937 rng(2);
  for (int8_t format : {image_t::PIXEL_BGR8, image_t::PIXEL_RGB8}) {
    const cv::Mat bgr = SmoothBgr(64, 48, static_cast<int>(rng() % 30));
    cv::Mat pixels = bgr.clone();
    if (format == image_t::PIXEL_RGB8) cv::cvtColor(bgr, pixels, cv::COLOR_BGR2RGB);
    cv::Mat out;
    const image_t png = Named(ImageToMessage(pixels, format, image_t::COMPRESSION_PNG));
    EXPECT_EQ(png.row_stride, 0);
    ASSERT_EQ(ImageMessageToBgr(png, &out), "");
    EXPECT_EQ(MaxDifference(out, bgr), 0.0);
    const image_t jpeg = Named(ImageToMessage(pixels, format, image_t::COMPRESSION_JPEG, 98));
    ASSERT_EQ(ImageMessageToBgr(jpeg, &out), "");
    EXPECT_LT(MaxDifference(out, bgr), 24.0);
    EXPECT_LT(cv::norm(out, bgr, cv::NORM_L1) / static_cast<double>(bgr.total() * 3), 2.0);
  }
}

TEST(MessageConvertTest, EveryBayerPatternDemosaicsToTheSceneColours) {
  // A flat colour, mosaiced by the pattern's definition (top-left cell read
  // row by row), must come back as that colour: this pins the mapping from
  // GenICam's names to OpenCV's.
  const cv::Vec3b colour(30, 120, 210);
  const cv::Mat flat(16, 20, CV_8UC3, cv::Scalar(colour[0], colour[1], colour[2]));
  for (int8_t format : {image_t::PIXEL_BAYER_RG8, image_t::PIXEL_BAYER_GR8,
                        image_t::PIXEL_BAYER_GB8, image_t::PIXEL_BAYER_BG8}) {
    const cv::Mat mosaic = MosaicBayer(flat, format);
    for (const int8_t compression : {image_t::COMPRESSION_NONE, image_t::COMPRESSION_PNG}) {
      cv::Mat out;
      ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(mosaic, format, compression)), &out), "");
      const cv::Vec3b centre = out.at<cv::Vec3b>(8, 10);
      EXPECT_EQ(centre, colour) << PixelFormatName(format);
    }
  }
}

TEST(MessageConvertTest, YuyvDecodes) {
  // Grey YUYV (U = V = 128): every channel is the luma, scaled from video
  // range (16-235) to full range.
  cv::Mat yuyv(4, 8, CV_8UC2, cv::Scalar(90, 128));
  cv::Mat out;
  ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(yuyv, image_t::PIXEL_YUYV)), &out), "");
  const double expected = (90 - 16) * 255.0 / 219.0;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at<cv::Vec3b>(2, 3)[c], expected, 1.0);
}

TEST(MessageConvertTest, ABgrViewSharesTheMessagesBytes) {
  const image_t image = Named(ImageToMessage(SmoothBgr(8, 6, 0), image_t::PIXEL_BGR8));
  cv::Mat view;
  ASSERT_EQ(ImageMessageToBgr(image, &view, ImageCopy::kViewWhenPossible), "");
  EXPECT_EQ(view.data, image.data.data());
  cv::Mat copy;
  ASSERT_EQ(ImageMessageToBgr(image, &copy), "");
  EXPECT_NE(copy.data, image.data.data());
}

TEST(MessageConvertTest, DecodingIntoAViewNeverWritesIntoTheViewedMessage) {
  // The services reuse their Mats from set to set: a view of the last
  // message must not be written into when the next one needs converting.
  const image_t first = Named(ImageToMessage(SmoothBgr(8, 6, 0), image_t::PIXEL_BGR8));
  const std::vector<uint8_t> before = first.data;
  cv::Mat reused;
  ASSERT_EQ(ImageMessageToBgr(first, &reused, ImageCopy::kViewWhenPossible), "");
  cv::Mat rgb;
  cv::cvtColor(SmoothBgr(8, 6, 50), rgb, cv::COLOR_BGR2RGB);
  ASSERT_EQ(ImageMessageToBgr(Named(ImageToMessage(rgb, image_t::PIXEL_RGB8)), &reused), "");
  ASSERT_EQ(ImageMessageToMono(Named(ImageToMessage(rgb, image_t::PIXEL_RGB8)), &reused), "");
  EXPECT_EQ(first.data, before);
  EXPECT_GT(MaxDifference(reused, cv::Mat(6, 8, CV_8UC1, cv::Scalar(0))), 0.0);
  // A buffer the Mat owns is reused.
  cv::Mat owned(6, 8, CV_8UC3);
  const uint8_t* buffer = owned.data;
  ASSERT_EQ(ImageMessageToBgr(first, &owned), "");
  EXPECT_EQ(owned.data, buffer);
}

TEST(MessageConvertTest, ImageToMessageRejectsATypeThatDoesNotFitTheFormat) {
  const cv::Mat bgr(4, 4, CV_8UC3);
  EXPECT_THROW(ImageToMessage(bgr, image_t::PIXEL_MONO8), std::invalid_argument);
  EXPECT_THROW(
      ImageToMessage(cv::Mat(4, 4, CV_8UC1), image_t::PIXEL_BAYER_RG8, image_t::COMPRESSION_JPEG),
      std::invalid_argument);
  EXPECT_THROW(ImageToMessage(bgr, 42), std::invalid_argument);
}

// One malformation of a valid raw BGR message, and what the reason must name.
struct Malformation {
  const char* name;
  void (*apply)(image_t*);
  const char* reason;
};

const Malformation kMalformations[] = {
    {"no camera", [](image_t* m) { m->camera.clear(); }, "camera"},
    {"zero width", [](image_t* m) { m->width = 0; }, "width"},
    {"huge height", [](image_t* m) { m->height = 1 << 20; }, "height"},
    {"unknown format", [](image_t* m) { m->pixel_format = 42; }, "pixel_format"},
    {"unknown compression", [](image_t* m) { m->compression = 9; }, "compression"},
    {"short stride", [](image_t* m) { m->row_stride -= 1; }, "row_stride"},
    {"size field wrong", [](image_t* m) { m->size += 1; }, "size"},
    {"truncated data",
     [](image_t* m) {
       // erase, not resize: GCC 12 cannot see the size stays >= 7 and warns.
       m->data.erase(m->data.end() - 7, m->data.end());
       m->size = static_cast<int32_t>(m->data.size());
     },
     "size"},
    {"wider than sent", [](image_t* m) { m->width += 1; }, "row_stride"},
    {"taller than sent", [](image_t* m) { m->height += 1; }, "size"},
    {"format wider than sent",
     [](image_t* m) {
       m->pixel_format = image_t::PIXEL_YUYV;
       m->row_stride = 2 * m->width;
     },
     "size"},
    {"stage count wrong", [](image_t* m) { m->num_stage_times = 3; }, "num_stage_times"},
    {"negative stage time",
     [](image_t* m) {
       m->stage_times = {MakeStageTime("capture", -5, 0)};
       m->num_stage_times = 1;
     },
     "duration_us"},
    {"negative time", [](image_t* m) { m->trigger_utime = -1; }, "trigger_utime"},
    {"NaN exposure", [](image_t* m) { m->exposure_us = std::numeric_limits<float>::quiet_NaN(); },
     "exposure_us"},
    {"garbage as PNG",
     [](image_t* m) {
       m->compression = image_t::COMPRESSION_PNG;
       m->row_stride = 0;
     },
     "data"},
    {"PNG with a stride",
     [](image_t* m) {
       *m =
           Named(ImageToMessage(SmoothBgr(8, 6, 0), image_t::PIXEL_BGR8, image_t::COMPRESSION_PNG));
       m->row_stride = 24;
     },
     "row_stride"},
    {"JPEG of a mosaic",
     [](image_t* m) {
       m->compression = image_t::COMPRESSION_JPEG;
       m->pixel_format = image_t::PIXEL_BAYER_RG8;
       m->row_stride = 0;
     },
     "compression"},
};

TEST(MessageConvertTest, MalformedImagesAreRejectedWithTheFieldAtFault) {
  for (const Malformation& malformation : kMalformations) {
    image_t image = Named(ImageToMessage(SmoothBgr(8, 6, 0), image_t::PIXEL_BGR8));
    malformation.apply(&image);
    const std::string reason = ValidateImageMessage(image);
    EXPECT_NE(reason.find(malformation.reason), std::string::npos)
        << malformation.name << ": " << reason;
    cv::Mat out;
    EXPECT_EQ(ImageMessageToBgr(image, &out), reason) << malformation.name;
    EXPECT_EQ(ImageMessageToMono(image, &out), reason) << malformation.name;
  }
}

TEST(MessageConvertTest, CompressedDataThatDoesNotDecodeToTheSizeIsRejected) {
  const cv::Mat bgr = SmoothBgr(16, 12, 0);
  cv::Mat out;
  // A PNG of another size.
  image_t image = Named(ImageToMessage(bgr, image_t::PIXEL_BGR8, image_t::COMPRESSION_PNG));
  image.width = 8;
  EXPECT_NE(ImageMessageToBgr(image, &out).find("16x12"), std::string::npos);
  // A grey PNG sent as colour.
  image = Named(ImageToMessage(cv::Mat(12, 16, CV_8UC1, cv::Scalar(9)), image_t::PIXEL_MONO8,
                               image_t::COMPRESSION_PNG));
  image.pixel_format = image_t::PIXEL_BGR8;
  EXPECT_NE(ImageMessageToBgr(image, &out).find("3-channel"), std::string::npos);
  // A PNG cut short, and one with its body replaced by random bytes.
  image = Named(ImageToMessage(bgr, image_t::PIXEL_BGR8, image_t::COMPRESSION_PNG));
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    image_t broken = image;
    if (trial % 2 == 0) {
      broken.data.resize(8 + rng() % (image.data.size() - 8));
    } else {
      for (size_t i = 8 + rng() % 16; i < broken.data.size(); i += 1 + rng() % 5)
        broken.data[i] = static_cast<uint8_t>(rng());
    }
    broken.size = static_cast<int32_t>(broken.data.size());
    const std::string reason = ImageMessageToBgr(broken, &out);
    if (reason.empty()) {  // a corruption PNG's checksums missed: still the right size
      EXPECT_EQ(out.size(), bgr.size());
    } else {
      EXPECT_EQ(reason.rfind("cam0: ", 0), 0u) << reason;
    }
  }
}

VoxelCloud RandomCloud(std::mt19937& rng) {
  VoxelCloud cloud;
  cloud.grid.origin = Vec3(-10.5, 3.25, 7.0 + static_cast<double>(rng() % 10));
  cloud.grid.voxel_size = 0.5 + static_cast<double>(rng() % 4);
  cloud.grid.dims = {1 + static_cast<int>(rng() % 40), 1 + static_cast<int>(rng() % 40),
                     1 + static_cast<int>(rng() % 40)};
  for (int64_t i = 0; i < cloud.grid.NumVoxels(); ++i) {
    if (rng() % 7 != 0) continue;
    cloud.voxels.push_back(static_cast<int32_t>(i));
    cloud.labels.push_back(rng() % 5 == 0 ? kLabelMarker : kLabelBody);
  }
  return cloud;
}

TEST(MessageConvertTest, VoxelCloudsRoundTrip) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 30; ++trial) {
    const VoxelCloud cloud = RandomCloud(rng);
    const voxel_cloud_t message = VoxelCloudToMessage(cloud);
    VoxelCloud back;
    ASSERT_EQ(VoxelCloudFromMessage(message, &back), "");
    EXPECT_EQ(back.voxels, cloud.voxels);
    EXPECT_EQ(back.labels, cloud.labels);
    EXPECT_EQ(back.grid.dims, cloud.grid.dims);
    EXPECT_EQ(back.grid.origin, cloud.grid.origin);
    EXPECT_EQ(back.grid.voxel_size, cloud.grid.voxel_size);
  }
}

TEST(MessageConvertTest, UnsortedVoxelsAreSortedWithTheirLabels) {
  VoxelCloud cloud;
  cloud.grid.dims = {4, 4, 4};
  voxel_cloud_t message = VoxelCloudToMessage(cloud);
  message.voxels = {9, 2, 40};
  message.labels = {1, 0, 0};
  message.num_voxels = 3;
  ASSERT_EQ(VoxelCloudFromMessage(message, &cloud), "");
  EXPECT_EQ(cloud.voxels, (std::vector<int32_t>{2, 9, 40}));
  EXPECT_EQ(cloud.labels, (std::vector<uint8_t>{kLabelBody, kLabelMarker, kLabelBody}));
}

TEST(MessageConvertTest, MalformedVoxelCloudsAreRejectedWithTheFieldAtFault) {
  std::mt19937 rng(5);
  VoxelCloud cloud = RandomCloud(rng);
  while (cloud.voxels.size() < 2) cloud = RandomCloud(rng);
  const voxel_cloud_t good = VoxelCloudToMessage(cloud);
  const int32_t total = good.dims[0] * good.dims[1] * good.dims[2];
  const std::vector<std::pair<std::function<void(voxel_cloud_t*)>, const char*>> cases = {
      {[](voxel_cloud_t* m) { m->dims[1] = 0; }, "dims[1]"},
      {[](voxel_cloud_t* m) { m->dims[0] = m->dims[1] = m->dims[2] = 2000; }, "dims"},
      {[](voxel_cloud_t* m) { m->voxel_size = -1; }, "voxel_size"},
      {[](voxel_cloud_t* m) { m->grid_origin[2] = std::numeric_limits<double>::infinity(); },
       "grid_origin"},
      {[total](voxel_cloud_t* m) { m->voxels.back() = total; }, "voxels"},
      {[](voxel_cloud_t* m) { m->voxels.front() = -1; }, "voxels"},
      {[](voxel_cloud_t* m) { m->voxels[1] = m->voxels[0]; }, "each index once"},
      {[](voxel_cloud_t* m) { m->num_voxels += 1; }, "num_voxels"},
      {[](voxel_cloud_t* m) { m->labels.pop_back(); }, "num_voxels"},
      {[](voxel_cloud_t* m) { m->num_stage_times = 2; }, "num_stage_times"},
  };
  for (const auto& [apply, reason] : cases) {
    voxel_cloud_t message = good;
    apply(&message);
    VoxelCloud out;
    const std::string error = VoxelCloudFromMessage(message, &out);
    EXPECT_NE(error.find(reason), std::string::npos) << reason << ": " << error;
  }
}

TEST(MessageConvertTest, ShapesRoundTripAndMalformedOnesAreRejected) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> coordinate(-100, 100);
  ShapeEstimate shape;
  shape.valid = true;
  for (int i = 0; i < 50; ++i) {
    shape.centerline.push_back(Vec3(coordinate(rng), coordinate(rng), coordinate(rng)));
    shape.arc_length.push_back(i * 1.0);
    shape.curvature.push_back(coordinate(rng) * 1e-4);
  }
  shape.markers = {Vec3(1, 2, 3), Vec3(4, 5, 6)};
  shape.marker_arc_length = {10, 20};
  shape.marker_std = {0.05, 0.08};
  shape.tip = shape.centerline.back();
  shape.length = 49;
  shape.silhouette_residual_mm = 0.03;
  ShapeEstimate back;
  shape_t message = ShapeToMessage(shape);
  ASSERT_EQ(ShapeFromMessage(message, &back), "");
  EXPECT_EQ(back.centerline, shape.centerline);
  EXPECT_EQ(back.curvature, shape.curvature);
  EXPECT_EQ(back.markers, shape.markers);
  EXPECT_EQ(back.marker_arc_length, shape.marker_arc_length);
  EXPECT_EQ(back.marker_std, shape.marker_std);
  EXPECT_EQ(back.tip, shape.tip);
  EXPECT_EQ(back.silhouette_residual_mm, shape.silhouette_residual_mm);

  ShapeEstimate failed;
  failed.error = "no body";
  ASSERT_EQ(ShapeFromMessage(ShapeToMessage(failed), &back), "");
  EXPECT_FALSE(back.valid);
  EXPECT_EQ(back.error, "no body");

  message.num_points = 3;
  EXPECT_NE(ShapeFromMessage(message, &back).find("num_points"), std::string::npos);
  message = ShapeToMessage(shape);
  message.centerline[4][1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(ShapeFromMessage(message, &back).find("finite"), std::string::npos);
  message = ShapeToMessage(shape);
  message.marker_arc_length.pop_back();
  EXPECT_NE(ShapeFromMessage(message, &back).find("num_markers"), std::string::npos);
  message = ShapeToMessage(shape);
  message.marker_std_mm.pop_back();
  EXPECT_NE(ShapeFromMessage(message, &back).find("num_markers"), std::string::npos);
  message = ShapeToMessage(shape);
  message.marker_std_mm[0] = std::numeric_limits<double>::infinity();
  EXPECT_NE(ShapeFromMessage(message, &back).find("finite"), std::string::npos);
}

TEST(MessageConvertTest, StageTimesMergeByTheSlowestImage) {
  std::vector<stage_time_t> stages;
  MergeStageTime(MakeStageTime("capture", 100, 1000), &stages);
  MergeStageTime(MakeStageTime("capture", 300, 900), &stages);
  MergeStageTime(MakeStageTime("debayer", 50, 1100), &stages);
  ASSERT_EQ(stages.size(), 2u);
  const stage_time_t* capture = FindStageTime(stages, "capture");
  ASSERT_NE(capture, nullptr);
  EXPECT_EQ(capture->duration_us, 300);
  EXPECT_EQ(capture->end_utime, 1000);
  EXPECT_EQ(FindStageTime(stages, "shape"), nullptr);
}

}  // namespace
}  // namespace shapesense
