#include "services/capture/preview_publisher.h"

#include <pthread.h>
#include <sched.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "runtime/host_clock.h"
#include "runtime/lcm/channels.h"

namespace shapesense {
namespace {

constexpr auto kPopTimeout = std::chrono::milliseconds(100);  // bounds the reaction to a stop

cv::Mat Downscaled(const cv::Mat& image, int width) {
  if (image.cols <= width) return image;
  const int height = std::max(
      1, static_cast<int>(std::lround(static_cast<double>(image.rows) * width / image.cols)));
  cv::Mat small;
  cv::resize(image, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return small;
}

}  // namespace

std::string PreviewOptions::Validate() const {
  if (!(rate_hz >= 0.0 && rate_hz <= 30.0)) {
    return "rate_hz: expected 0-30, got " + std::to_string(rate_hz);
  }
  if (width < 32 || width > 1280) return "width: expected 32-1280, got " + std::to_string(width);
  if (jpeg_quality < 10 || jpeg_quality > 100) {
    return "jpeg_quality: expected 10-100, got " + std::to_string(jpeg_quality);
  }
  return "";
}

int64_t PreviewEvery(const PreviewOptions& options, double trigger_rate_hz) {
  if (!(options.rate_hz > 0.0)) return 0;
  return std::max<int64_t>(1, static_cast<int64_t>(std::ceil(trigger_rate_hz / options.rate_hz)));
}

image_t PreviewMessage(const std::string& camera, const CameraFrame& frame,
                       const PreviewOptions& options, int64_t publish_utime) {
  const cv::Mat small = Downscaled(frame.image, options.width);
  image_t message{};
  message.header.utime = publish_utime;
  message.camera = camera;
  message.width = small.cols;
  message.height = small.rows;
  message.row_stride = 0;
  message.pixel_format = small.channels() == 1 ? image_t::PIXEL_MONO8 : image_t::PIXEL_BGR8;
  message.compression = image_t::COMPRESSION_JPEG;
  message.exposure_us = static_cast<float>(frame.exposure_us);
  message.gain_db = static_cast<float>(frame.gain_db);
  message.trigger_seq = frame.trigger_seq;
  message.trigger_utime = frame.trigger_utime;
  message.frame_id = frame.frame_id;
  message.device_timestamp_ns = frame.device_timestamp_ns;
  message.host_utime = frame.host_utime;
  cv::imencode(".jpg", small, message.data, {cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality});
  message.size = static_cast<int32_t>(message.data.size());
  return message;
}

PreviewPublisher::PreviewPublisher(const PreviewOptions& options, double trigger_rate_hz,
                                   Publish publish)
    : options_(options),
      every_(PreviewEvery(options, trigger_rate_hz)),
      publish_(std::move(publish)),
      queue_(4),
      thread_([this] { Run(); }) {}

PreviewPublisher::~PreviewPublisher() {
  stopping_ = true;
  queue_.Close();
  thread_.join();
}

void PreviewPublisher::Offer(const std::string& camera, const CameraFrame& frame) {
  if (every_ == 0) return;
  const int64_t sequence = frame.trigger_seq >= 0 ? frame.trigger_seq : frame.frame_id;
  if (sequence % every_ != 0) return;
  Job job{camera, frame};
  job.frame.image = frame.image.clone();  // the backend may reuse its buffer
  queue_.Push(std::move(job));
}

void PreviewPublisher::Run() {
  // Pictures for people take only CPU nobody else wants: the capture
  // service may run at a raised priority (its triggers stand for hardware),
  // and an encode at that priority delayed the virtual rig's exposures.
  const sched_param idle{};
  pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle);
  while (!stopping_) {
    std::optional<Job> job = queue_.Pop(kPopTimeout);
    if (!job) continue;
    image_t message = PreviewMessage(job->camera, job->frame, options_, HostUtime());
    publish_(channels::Preview(job->camera), message);
    ++published_;
  }
}

}  // namespace shapesense
