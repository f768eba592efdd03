#include "services/capture/image_message.h"

#include <algorithm>
#include <stdexcept>

#include "runtime/lcm/image_codec.h"

namespace shapesense {
namespace {

stage_time_t CaptureStage(const CameraFrame& frame, int64_t trigger_utime) {
  stage_time_t stage;
  stage.stage = "capture";
  stage.duration_us = frame.host_utime - trigger_utime;
  stage.end_utime = frame.host_utime;
  return stage;
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
  image_t message = ImageToMessage(
      image, image.channels() == 3 ? image_t::PIXEL_BGR8 : image_t::PIXEL_MONO8,
      compression == ImageCompression::kPng ? image_t::COMPRESSION_PNG : image_t::COMPRESSION_NONE,
      /*jpeg_quality=*/95, png_level);
  message.header.seq = seq;
  message.header.utime = publish_utime;
  message.camera = camera;
  message.exposure_us = static_cast<float>(frame.exposure_us);
  message.gain_db = static_cast<float>(frame.gain_db);
  message.trigger_seq = frame.trigger_seq;
  message.trigger_utime = frame.trigger_utime > 0 ? frame.trigger_utime : frame.host_utime;
  message.frame_id = frame.frame_id;
  message.device_timestamp_ns = frame.device_timestamp_ns;
  message.host_utime = frame.host_utime;
  // The trigger and the publish are both this host's clock: the age is exact.
  message.header.data_age_us = std::max<int64_t>(0, publish_utime - message.trigger_utime);
  message.stage_times = {CaptureStage(frame, message.trigger_utime)};
  message.num_stage_times = 1;
  return message;
}

}  // namespace shapesense
