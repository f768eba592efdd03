#include "services/capture/image_message.h"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace shapesense {
namespace {

stage_time_t CaptureStage(const CameraFrame& frame, int64_t trigger_utime) {
  stage_time_t stage;
  stage.stage = "capture";
  stage.duration_us = frame.host_utime - trigger_utime;
  stage.end_utime = frame.host_utime;
  return stage;
}

void SetData(const cv::Mat& image, ImageCompression compression, int png_level, image_t* message) {
  if (compression == ImageCompression::kPng) {
    // Camera images are noisy: string matching finds little, and Huffman coding
    // alone is both smaller and faster than the default strategy.
    cv::imencode(".png", image, message->data,
                 {cv::IMWRITE_PNG_COMPRESSION, png_level, cv::IMWRITE_PNG_STRATEGY,
                  cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY});
    message->row_stride = 0;
  } else {
    const size_t row = image.cols * image.elemSize();
    message->data.resize(row * static_cast<size_t>(image.rows));
    for (int y = 0; y < image.rows; ++y) std::memcpy(&message->data[row * y], image.ptr(y), row);
    message->row_stride = static_cast<int32_t>(row);
  }
  message->size = static_cast<int32_t>(message->data.size());
}

cv::Mat DecodeRaw(const image_t& message, int type) {
  const cv::Mat rows(message.height, message.width, type, const_cast<uint8_t*>(message.data.data()),
                     static_cast<size_t>(message.row_stride));
  return rows.clone();
}

}  // namespace

ImageCompression ParseCompression(const std::string& name) {
  if (name == "none") return ImageCompression::kNone;
  if (name == "png") return ImageCompression::kPng;
  throw std::invalid_argument("compression: expected none or png, got '" + name + "'");
}

image_t ToImageMessage(const std::string& camera, const CameraFrame& frame, int64_t seq,
                       int64_t publish_utime, ImageCompression compression, int png_level) {
  const cv::Mat& image = frame.image;
  if (image.empty() || (image.type() != CV_8UC3 && image.type() != CV_8UC1)) {
    throw std::invalid_argument(camera + ": an image to publish must be 8-bit BGR or mono");
  }
  image_t message;
  message.header.seq = seq;
  message.header.utime = publish_utime;
  message.camera = camera;
  message.width = image.cols;
  message.height = image.rows;
  message.pixel_format = image.channels() == 3 ? image_t::PIXEL_BGR8 : image_t::PIXEL_MONO8;
  message.compression =
      compression == ImageCompression::kPng ? image_t::COMPRESSION_PNG : image_t::COMPRESSION_NONE;
  message.exposure_us = static_cast<float>(frame.exposure_us);
  message.gain_db = static_cast<float>(frame.gain_db);
  message.trigger_seq = frame.trigger_seq;
  message.trigger_utime = frame.trigger_utime > 0 ? frame.trigger_utime : frame.host_utime;
  message.device_timestamp_ns = frame.device_timestamp_ns;
  message.host_utime = frame.host_utime;
  message.stage_times = {CaptureStage(frame, message.trigger_utime)};
  message.num_stage_times = 1;
  SetData(image, compression, png_level, &message);
  return message;
}

cv::Mat DecodeImageMessage(const image_t& message) {
  const bool mono = message.pixel_format == image_t::PIXEL_MONO8;
  if (!mono && message.pixel_format != image_t::PIXEL_BGR8) return {};
  if (message.width <= 0 || message.height <= 0 ||
      message.size != static_cast<int32_t>(message.data.size()))
    return {};
  const int type = mono ? CV_8UC1 : CV_8UC3;
  if (message.compression == image_t::COMPRESSION_PNG) {
    cv::Mat image;
    try {
      image = cv::imdecode(message.data, mono ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
    } catch (const cv::Exception&) {
      return {};
    }
    if (image.cols != message.width || image.rows != message.height) return {};
    return image;
  }
  if (message.compression != image_t::COMPRESSION_NONE) return {};
  const int64_t row = static_cast<int64_t>(message.width) * (mono ? 1 : 3);
  if (message.row_stride < row ||
      static_cast<int64_t>(message.data.size()) <
          static_cast<int64_t>(message.row_stride) * (message.height - 1) + row) {
    return {};
  }
  return DecodeRaw(message, type);
}

}  // namespace shapesense
