#include "runtime/lcm/image_codec.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "libs/core/error.h"
#include "runtime/lcm/stage_times.h"

namespace shapesense {
namespace {

bool IsBayer(int8_t format) {
  return format >= image_t::PIXEL_BAYER_RG8 && format <= image_t::PIXEL_BAYER_BG8;
}

// OpenCV names a Bayer pattern by the second row's second and third pixels;
// GenICam (and image_t) by the top-left cell read row by row.
int BayerToBgrCode(int8_t format) {
  switch (format) {
    case image_t::PIXEL_BAYER_RG8:
      return cv::COLOR_BayerBG2BGR;
    case image_t::PIXEL_BAYER_GR8:
      return cv::COLOR_BayerGB2BGR;
    case image_t::PIXEL_BAYER_GB8:
      return cv::COLOR_BayerGR2BGR;
    default:
      return cv::COLOR_BayerRG2BGR;  // PIXEL_BAYER_BG8
  }
}

int BayerToGrayCode(int8_t format) {
  switch (format) {
    case image_t::PIXEL_BAYER_RG8:
      return cv::COLOR_BayerBG2GRAY;
    case image_t::PIXEL_BAYER_GR8:
      return cv::COLOR_BayerGB2GRAY;
    case image_t::PIXEL_BAYER_GB8:
      return cv::COLOR_BayerGR2GRAY;
    default:
      return cv::COLOR_BayerRG2GRAY;
  }
}

int CvTypeOf(int8_t format) {
  const int bytes = BytesPerPixel(format);
  return bytes == 1 ? CV_8UC1 : bytes == 2 ? CV_8UC2 : CV_8UC3;
}

bool CompressionAllowed(int8_t format, int8_t compression) {
  if (compression == image_t::COMPRESSION_NONE) return true;
  if (format == image_t::PIXEL_YUYV) return false;
  return compression == image_t::COMPRESSION_PNG || !IsBayer(format);
}

bool HasSignature(std::span<const uint8_t> data, int8_t compression) {
  static constexpr uint8_t kPng[] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  static constexpr uint8_t kJpeg[] = {0xFF, 0xD8, 0xFF};
  if (compression == image_t::COMPRESSION_PNG) {
    return data.size() >= sizeof(kPng) &&
           std::equal(std::begin(kPng), std::end(kPng), data.begin());
  }
  return data.size() >= sizeof(kJpeg) &&
         std::equal(std::begin(kJpeg), std::end(kJpeg), data.begin());
}

std::string ValidateImageGeometry(const image_t& image, std::span<const uint8_t> bytes) {
  for (const auto& [key, value] : {std::pair{"width", image.width}, {"height", image.height}}) {
    if (value < 1 || value > kMaxImageSide) {
      return Expected(key, "1-" + std::to_string(kMaxImageSide) + " px", std::to_string(value));
    }
  }
  if (BytesPerPixel(image.pixel_format) == 0) {
    return Expected("pixel_format", "one of the PIXEL_* constants",
                    std::to_string(image.pixel_format));
  }
  if (image.size < 0 || static_cast<size_t>(image.size) != bytes.size()) {
    return Expected("size", std::to_string(bytes.size()) + " (the bytes sent)",
                    std::to_string(image.size));
  }
  return {};
}

std::string ValidateRawLayout(const image_t& image) {
  const int64_t row_bytes = int64_t{image.width} * BytesPerPixel(image.pixel_format);
  if (image.row_stride < row_bytes) {
    return Expected("row_stride", ">= " + std::to_string(row_bytes) + " (width x bytes per pixel)",
                    std::to_string(image.row_stride));
  }
  const int64_t needed = int64_t{image.row_stride} * image.height;
  if (image.size != needed) {
    return Expected("size",
                    std::to_string(needed) + " bytes (row_stride " +
                        std::to_string(image.row_stride) + " x height " +
                        std::to_string(image.height) + ")",
                    std::to_string(image.size));
  }
  return {};
}

std::string ValidateCompressedLayout(const image_t& image, std::span<const uint8_t> bytes) {
  if (!CompressionAllowed(image.pixel_format, image.compression)) {
    return Expected("compression", "none for " + PixelFormatName(image.pixel_format),
                    image.compression == image_t::COMPRESSION_PNG ? "PNG" : "JPEG");
  }
  if (image.row_stride != 0) {
    return Expected("row_stride", "0 for a compressed image", std::to_string(image.row_stride));
  }
  if (!HasSignature(bytes, image.compression)) {
    return Expected(
        "data", image.compression == image_t::COMPRESSION_PNG ? "a PNG stream" : "a JPEG stream",
        "other bytes");
  }
  return {};
}

std::string ValidateImageTimes(const image_t& image) {
  if (image.header.utime < 0 || image.trigger_utime < 0 || image.host_utime < 0) {
    return Expected("header.utime, trigger_utime, host_utime", "times >= 0", "a negative one");
  }
  if (!std::isfinite(image.exposure_us) || image.exposure_us < 0 || !std::isfinite(image.gain_db)) {
    return Expected("exposure_us, gain_db", "finite numbers, exposure >= 0", "something else");
  }
  return ValidateStageTimes(image.num_stage_times, image.stage_times);
}

std::string ValidateImageFields(const image_t& image, std::span<const uint8_t> bytes) {
  if (std::string error = ValidateImageGeometry(image, bytes); !error.empty()) return error;
  const int8_t compression = image.compression;
  if (compression != image_t::COMPRESSION_NONE && compression != image_t::COMPRESSION_PNG &&
      compression != image_t::COMPRESSION_JPEG) {
    return Expected("compression", "one of the COMPRESSION_* constants",
                    std::to_string(compression));
  }
  std::string error = compression == image_t::COMPRESSION_NONE
                          ? ValidateRawLayout(image)
                          : ValidateCompressedLayout(image, bytes);
  return error.empty() ? ValidateImageTimes(image) : error;
}

std::string CameraPrefix(const image_t& image) {
  return (image.camera.empty() ? std::string("(unnamed camera)") : image.camera) + ": ";
}

// The pixels in the layout of pixel_format: a view of raw bytes, or decoded.
std::string PixelsOf(const image_t& image, std::span<const uint8_t> bytes, cv::Mat* pixels) {
  const int type = CvTypeOf(image.pixel_format);
  if (image.compression == image_t::COMPRESSION_NONE) {
    // A read-only view: cv::Mat has no const form.
    *pixels = cv::Mat(image.height, image.width, type, const_cast<uint8_t*>(bytes.data()),
                      static_cast<size_t>(image.row_stride));
    return {};
  }
  try {
    const cv::Mat stream(1, static_cast<int>(bytes.size()), CV_8UC1,
                         const_cast<uint8_t*>(bytes.data()));
    *pixels = cv::imdecode(stream, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    return Expected("data", "a decodable image", std::string("an error (") + e.what() + ")");
  }
  if (pixels->empty()) return Expected("data", "a decodable image", "undecodable bytes");
  if (pixels->type() != type || pixels->cols != image.width || pixels->rows != image.height) {
    return Expected("data",
                    "an 8-bit " + std::to_string(CV_MAT_CN(type)) + "-channel image of " +
                        std::to_string(image.width) + "x" + std::to_string(image.height),
                    std::to_string(pixels->channels()) + " channels (depth " +
                        std::to_string(pixels->depth()) + ") of " + std::to_string(pixels->cols) +
                        "x" + std::to_string(pixels->rows));
  }
  return {};
}

void ConvertToBgr(const cv::Mat& pixels, int8_t format, cv::Mat* bgr) {
  switch (format) {
    case image_t::PIXEL_MONO8:
      cv::cvtColor(pixels, *bgr, cv::COLOR_GRAY2BGR);
      break;
    case image_t::PIXEL_BGR8:
      pixels.copyTo(*bgr);
      break;
    case image_t::PIXEL_RGB8:
      cv::cvtColor(pixels, *bgr, cv::COLOR_RGB2BGR);
      break;
    case image_t::PIXEL_YUYV:
      cv::cvtColor(pixels, *bgr, cv::COLOR_YUV2BGR_YUYV);
      break;
    default:
      cv::cvtColor(pixels, *bgr, BayerToBgrCode(format));
      break;
  }
}

void ConvertToMono(const cv::Mat& pixels, int8_t format, cv::Mat* mono) {
  switch (format) {
    case image_t::PIXEL_MONO8:
      pixels.copyTo(*mono);
      break;
    case image_t::PIXEL_BGR8:
      cv::cvtColor(pixels, *mono, cv::COLOR_BGR2GRAY);
      break;
    case image_t::PIXEL_RGB8:
      cv::cvtColor(pixels, *mono, cv::COLOR_RGB2GRAY);
      break;
    case image_t::PIXEL_YUYV:
      cv::cvtColor(pixels, *mono, cv::COLOR_YUV2GRAY_YUYV);
      break;
    default:
      cv::cvtColor(pixels, *mono, BayerToGrayCode(format));
      break;
  }
}

// An output Mat may be a view (ImageCopy::kViewWhenPossible) of a message
// long gone: OpenCV would write into it when the size fits, so it is let go
// of first. One that owns its buffer is reused.
void ReleaseIfView(cv::Mat* out) {
  if (out->u == nullptr) out->release();
}

// The one shared path of ImageMessageToBgr and ImageMessageToMono.
template <class Convert>
std::string DecodeImage(const image_t& image, std::span<const uint8_t> bytes, Convert convert) {
  if (std::string error = ValidateImageMessage(image, bytes); !error.empty()) return error;
  cv::Mat pixels;
  if (std::string error = PixelsOf(image, bytes, &pixels); !error.empty())
    return CameraPrefix(image) + error;
  // A demosaic needs 2×2 cells, YUYV pairs of pixels; OpenCV asserts otherwise.
  if ((IsBayer(image.pixel_format) && (image.width < 2 || image.height < 2)) ||
      (image.pixel_format == image_t::PIXEL_YUYV && image.width % 2 != 0)) {
    return CameraPrefix(image) +
           Expected("width, height", "whole cells of the pixel format",
                    std::to_string(image.width) + "x" + std::to_string(image.height));
  }
  try {
    convert(pixels);
  } catch (const cv::Exception& e) {
    return CameraPrefix(image) + "pixels could not be converted: " + e.what();
  }
  return {};
}

}  // namespace

int BytesPerPixel(int8_t pixel_format) {
  switch (pixel_format) {
    case image_t::PIXEL_MONO8:
    case image_t::PIXEL_BAYER_RG8:
    case image_t::PIXEL_BAYER_GR8:
    case image_t::PIXEL_BAYER_GB8:
    case image_t::PIXEL_BAYER_BG8:
      return 1;
    case image_t::PIXEL_YUYV:
      return 2;
    case image_t::PIXEL_BGR8:
    case image_t::PIXEL_RGB8:
      return 3;
    default:
      return 0;
  }
}

std::string PixelFormatName(int8_t pixel_format) {
  switch (pixel_format) {
    case image_t::PIXEL_MONO8:
      return "MONO8";
    case image_t::PIXEL_BGR8:
      return "BGR8";
    case image_t::PIXEL_RGB8:
      return "RGB8";
    case image_t::PIXEL_BAYER_RG8:
      return "BAYER_RG8";
    case image_t::PIXEL_BAYER_GR8:
      return "BAYER_GR8";
    case image_t::PIXEL_BAYER_GB8:
      return "BAYER_GB8";
    case image_t::PIXEL_BAYER_BG8:
      return "BAYER_BG8";
    case image_t::PIXEL_YUYV:
      return "YUYV";
    default:
      return "unknown (" + std::to_string(pixel_format) + ")";
  }
}

std::string ValidateImageMessage(const image_t& image) {
  return ValidateImageMessage(image, image.data);
}

std::string ValidateImageMessage(const image_t& image, std::span<const uint8_t> bytes) {
  if (image.camera.empty()) return "(unnamed camera): camera: expected a name, got none";
  const std::string error = ValidateImageFields(image, bytes);
  return error.empty() ? error : CameraPrefix(image) + error;
}

std::string ImageMessageToBgr(const image_t& image, cv::Mat* bgr, ImageCopy copy) {
  return ImageMessageToBgr(image, image.data, bgr, copy);
}

std::string ImageMessageToBgr(const image_t& image, std::span<const uint8_t> bytes, cv::Mat* bgr,
                              ImageCopy copy) {
  ReleaseIfView(bgr);
  return DecodeImage(image, bytes, [&](const cv::Mat& pixels) {
    // A view of the message's bytes when allowed; a decoded image is a
    // fresh buffer already.
    const bool compressed = image.compression != image_t::COMPRESSION_NONE;
    const bool as_is = image.pixel_format == image_t::PIXEL_BGR8 &&
                       (compressed || copy == ImageCopy::kViewWhenPossible);
    if (as_is) {
      *bgr = pixels;
    } else {
      ConvertToBgr(pixels, image.pixel_format, bgr);
    }
  });
}

std::string ImageMessageToMono(const image_t& image, cv::Mat* mono) {
  return DecodeImage(image, image.data, [&](const cv::Mat& pixels) {
    ConvertToMono(pixels, image.pixel_format, mono);
  });
}

image_t ImageToMessage(const cv::Mat& pixels, int8_t pixel_format, int8_t compression,
                       int jpeg_quality, int png_level) {
  if (BytesPerPixel(pixel_format) == 0 || pixels.type() != CvTypeOf(pixel_format) ||
      pixels.empty() || pixels.cols > kMaxImageSide || pixels.rows > kMaxImageSide) {
    throw std::invalid_argument("ImageToMessage: an image of type " +
                                std::to_string(pixels.type()) + " does not fit " +
                                PixelFormatName(pixel_format));
  }
  if (!CompressionAllowed(pixel_format, compression) || compression < 0 ||
      compression > image_t::COMPRESSION_JPEG) {
    throw std::invalid_argument("ImageToMessage: " + PixelFormatName(pixel_format) +
                                " cannot be sent with compression " + std::to_string(compression));
  }
  image_t image{};
  image.width = pixels.cols;
  image.height = pixels.rows;
  image.pixel_format = pixel_format;
  image.compression = compression;
  if (compression == image_t::COMPRESSION_NONE) {
    image.row_stride = pixels.cols * BytesPerPixel(pixel_format);
    image.data.resize(static_cast<size_t>(image.row_stride) * static_cast<size_t>(pixels.rows));
    for (int y = 0; y < pixels.rows; ++y) {
      std::memcpy(
          image.data.data() + static_cast<size_t>(y) * static_cast<size_t>(image.row_stride),
          pixels.ptr(y), static_cast<size_t>(image.row_stride));
    }
  } else if (compression == image_t::COMPRESSION_PNG) {
    // Camera images are noisy: string matching finds little, and Huffman coding
    // alone is both smaller and faster than the default strategy.
    cv::imencode(".png", pixels, image.data,
                 {cv::IMWRITE_PNG_COMPRESSION, png_level, cv::IMWRITE_PNG_STRATEGY,
                  cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY});
  } else {
    cv::imencode(".jpg", pixels, image.data, {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
  }
  image.size = static_cast<int32_t>(image.data.size());
  return image;
}

cv::Mat MosaicBayer(const cv::Mat& bgr, int8_t bayer_format) {
  if (bgr.type() != CV_8UC3 || !IsBayer(bayer_format)) {
    throw std::invalid_argument("MosaicBayer: expected 8-bit BGR and a PIXEL_BAYER_* format");
  }
  // Colour (as a BGR channel index) of each pixel of the top-left 2×2 cell.
  static constexpr int kCells[4][4] = {
      {2, 1, 1, 0},  // RG: R G / G B
      {1, 2, 0, 1},  // GR: G R / B G
      {1, 0, 2, 1},  // GB: G B / R G
      {0, 1, 1, 2},  // BG: B G / G R
  };
  const int* cell = kCells[bayer_format - image_t::PIXEL_BAYER_RG8];
  cv::Mat mosaic(bgr.size(), CV_8UC1);
  for (int y = 0; y < bgr.rows; ++y) {
    const cv::Vec3b* in = bgr.ptr<cv::Vec3b>(y);
    uint8_t* out = mosaic.ptr<uint8_t>(y);
    for (int x = 0; x < bgr.cols; ++x) out[x] = in[x][cell[2 * (y % 2) + x % 2]];
  }
  return mosaic;
}

}  // namespace shapesense
