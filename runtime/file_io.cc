#include "runtime/file_io.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "libs/core/error.h"

namespace shapesense {

std::string ReadTextFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot be opened for reading");
  std::ostringstream contents;
  contents << in.rdbuf();
  if (in.bad()) throw InputError(path.string() + ": read failed");
  return contents.str();
}

void WriteFileAtomically(const std::filesystem::path& path, const std::string& contents) {
  std::filesystem::path temporary = path;
  temporary += ".partial";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path.string() + ": cannot be opened for writing");
    out << contents;
    out.flush();
    if (!out) throw InputError(path.string() + ": write failed");
  }
  std::filesystem::rename(temporary, path);
}

cv::Mat ReadBgrImage(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path.string() + ": missing");
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw InputError(path.string() + ": not a readable image");
  if (image.depth() != CV_8U) throw InputError(path.string() + ": expected 8-bit pixels");
  if (image.channels() == 3) return image;
  cv::Mat bgr;
  if (image.channels() == 1) {
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  } else {
    throw InputError(path.string() + ": expected a BGR image");
  }
  return bgr;
}

void WritePng(const std::filesystem::path& path, const cv::Mat& image) {
  std::vector<uint8_t> encoded;
  if (!cv::imencode(".png", image, encoded)) {
    throw InputError(path.string() + ": could not encode PNG");
  }
  WriteFileAtomically(path, std::string(encoded.begin(), encoded.end()));
}

}  // namespace shapesense
