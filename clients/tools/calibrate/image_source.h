#pragma once

// Where the calibration tools get their pictures. Today: image folders.
// Live grabbing through the capture service (over LCM) will be another
// implementation of these interfaces once that service exists; the tools
// only see the interfaces.

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace shapesense {

struct NamedImage {
  std::string name;    // e.g. the file name; used for overlays and messages
  std::string source;  // where it came from, for messages (e.g. the file's path)
  cv::Mat image;       // 8-bit BGR
};

// One camera's pictures, one at a time.
class ImageSource {
 public:
  virtual ~ImageSource() = default;
  virtual std::string Describe() const = 0;
  // How many pictures Next() will give (for progress).
  virtual int Count() const = 0;
  // The next picture; nullopt when there are no more. Throws InputError
  // naming the picture when it cannot be read.
  virtual std::optional<NamedImage> Next() = 0;
};

// Views taken by several cameras at the same instants.
struct NamedFrameSet {
  std::string name;                  // the view's name
  std::vector<std::string> sources;  // per camera, for messages
  std::vector<cv::Mat> images;       // per camera; empty where a camera has no picture
};

class FrameSetSource {
 public:
  virtual ~FrameSetSource() = default;
  virtual std::string Describe() const = 0;
  virtual const std::vector<std::string>& CameraNames() const = 0;
  virtual int Count() const = 0;
  virtual std::optional<NamedFrameSet> Next() = 0;
};

// Is this file name one of an image (.png .jpg .jpeg .bmp .tif .tiff .pgm .ppm)?
bool IsImageFileName(const std::filesystem::path& path);

// The image files of a folder (not its subfolders) in name order. Throws
// InputError when the folder is missing or holds no image files.
class FolderImageSource : public ImageSource {
 public:
  explicit FolderImageSource(std::filesystem::path folder);
  std::string Describe() const override { return folder_.string(); }
  int Count() const override { return static_cast<int>(files_.size()); }
  std::optional<NamedImage> Next() override;

 private:
  std::filesystem::path folder_;
  std::vector<std::filesystem::path> files_;
  size_t next_ = 0;
};

// DIR/<camera>/<view file>: one subfolder per camera (its name is the
// camera's), views matched across cameras by file name, in name order. A
// camera without a file of some view has an empty image there. Throws
// InputError when DIR is missing, has no camera folders, or a camera folder
// holds no image files.
class FolderFrameSetSource : public FrameSetSource {
 public:
  explicit FolderFrameSetSource(std::filesystem::path folder);
  std::string Describe() const override { return folder_.string(); }
  const std::vector<std::string>& CameraNames() const override { return cameras_; }
  int Count() const override { return static_cast<int>(views_.size()); }
  std::optional<NamedFrameSet> Next() override;

 private:
  std::filesystem::path folder_;
  std::vector<std::string> cameras_;
  std::vector<std::string> views_;
  size_t next_ = 0;
};

// The camera subfolders of DIR, in name order (InputError when DIR is
// missing or has none).
std::vector<std::string> CameraFolders(const std::filesystem::path& folder);

}  // namespace shapesense
