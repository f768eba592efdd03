#include "libs/calibration/background.h"

#include <algorithm>
#include <stdexcept>

namespace shapesense {
namespace {

void CheckFrames(const std::vector<cv::Mat>& frames) {
  if (frames.empty()) throw std::invalid_argument("MedianImage: no frames");
  for (const cv::Mat& frame : frames) {
    if (frame.depth() != CV_8U || frame.type() != frames[0].type() ||
        frame.size() != frames[0].size()) {
      throw std::invalid_argument("MedianImage: frames must be 8-bit, of one size and type");
    }
  }
}

// Median of values (reordered in place), upper-rounded mean of the middle two when even.
uint8_t Median(std::vector<uint8_t>& values) {
  const size_t half = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half),
                   values.end());
  const int upper = values[half];
  if (values.size() % 2 == 1) return static_cast<uint8_t>(upper);
  const int lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(half));
  return static_cast<uint8_t>((lower + upper + 1) / 2);
}

}  // namespace

cv::Mat MedianImage(const std::vector<cv::Mat>& frames, const CalibrationProgress& progress) {
  CheckFrames(frames);
  cv::Mat median(frames[0].size(), frames[0].type());
  const int values_per_row = frames[0].cols * frames[0].channels();
  std::vector<uint8_t> values(frames.size());
  for (int y = 0; y < median.rows; ++y) {
    uint8_t* out = median.ptr<uint8_t>(y);
    for (int i = 0; i < values_per_row; ++i) {
      for (size_t f = 0; f < frames.size(); ++f) values[f] = frames[f].ptr<uint8_t>(y)[i];
      out[i] = Median(values);
    }
    if (progress && y % 32 == 31) progress(static_cast<double>(y + 1) / median.rows, "median");
  }
  if (progress) progress(1.0, "median");
  return median;
}

}  // namespace shapesense
