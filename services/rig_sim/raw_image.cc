#include "services/rig_sim/raw_image.h"

#include <opencv2/imgproc.hpp>

#include "libs/camera/genicam_pixel_formats.h"

namespace shapesense {
namespace {

// The 2x2 Bayer tile, row by row, as BGR channel indices; nullptr when not Bayer.
const int* BayerTile(uint32_t pixel_format) {
  static constexpr int kRg[4] = {2, 1, 1, 0};
  static constexpr int kGr[4] = {1, 2, 0, 1};
  static constexpr int kGb[4] = {1, 0, 2, 1};
  static constexpr int kBg[4] = {0, 1, 1, 2};
  switch (pixel_format) {
    case genicam::kBayerRg8:
      return kRg;
    case genicam::kBayerGr8:
      return kGr;
    case genicam::kBayerGb8:
      return kGb;
    case genicam::kBayerBg8:
      return kBg;
    default:
      return nullptr;
  }
}

void Mosaic(const cv::Mat& bgr, const int* tile, uint8_t* out) {
  for (int y = 0; y < bgr.rows; ++y) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(y);
    uint8_t* out_row = out + static_cast<size_t>(y) * bgr.cols;
    const int* pair = tile + 2 * (y % 2);
    for (int x = 0; x < bgr.cols; ++x) out_row[x] = row[x][pair[x % 2]];
  }
}

}  // namespace

int RawBytesPerPixel(uint32_t pixel_format) {
  if (pixel_format == genicam::kRgb8 || pixel_format == genicam::kBgr8) return 3;
  if (pixel_format == genicam::kMono16) return 2;
  if (pixel_format == genicam::kMono8 || BayerTile(pixel_format) != nullptr) return 1;
  return 0;
}

bool EncodeRawImage(const cv::Mat& bgr, uint32_t pixel_format, int width, int height, uint8_t* out,
                    size_t out_size) {
  const int bytes = RawBytesPerPixel(pixel_format);
  if (bytes == 0 || width <= 0 || height <= 0 || bgr.type() != CV_8UC3) return false;
  if (out_size < static_cast<size_t>(width) * height * bytes) return false;
  cv::Mat image = bgr;
  if (bgr.cols != width || bgr.rows != height) cv::resize(bgr, image, cv::Size(width, height));
  if (const int* tile = BayerTile(pixel_format)) {
    Mosaic(image, tile, out);
    return true;
  }
  if (pixel_format == genicam::kBgr8) {
    image.copyTo(cv::Mat(height, width, CV_8UC3, out));
  } else if (pixel_format == genicam::kRgb8) {
    cv::cvtColor(image, cv::Mat(height, width, CV_8UC3, out), cv::COLOR_BGR2RGB);
  } else if (pixel_format == genicam::kMono8) {
    cv::cvtColor(image, cv::Mat(height, width, CV_8UC1, out), cv::COLOR_BGR2GRAY);
  } else {
    cv::Mat grey;
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    grey.convertTo(cv::Mat(height, width, CV_16UC1, out), CV_16U, 257.0);
  }
  return true;
}

}  // namespace shapesense
