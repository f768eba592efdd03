#include "clients/tools/calibrate/image_source.h"

#include <algorithm>
#include <cctype>
#include <set>

#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

std::vector<fs::path> ImageFiles(const fs::path& folder) {
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && IsImageFileName(entry.path())) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

void RequireFolder(const fs::path& folder) {
  if (!fs::is_directory(folder)) throw InputError(folder.string() + ": no such folder");
}

}  // namespace

bool IsImageFileName(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::set<std::string> kExtensions = {".png", ".jpg",  ".jpeg", ".bmp",
                                                    ".tif", ".tiff", ".pgm",  ".ppm"};
  return kExtensions.contains(extension);
}

FolderImageSource::FolderImageSource(fs::path folder) : folder_(std::move(folder)) {
  RequireFolder(folder_);
  files_ = ImageFiles(folder_);
  if (files_.empty()) {
    throw InputError(folder_.string() +
                     ": no images (.png .jpg .jpeg .bmp .tif .tiff .pgm .ppm) in the folder");
  }
}

std::optional<NamedImage> FolderImageSource::Next() {
  if (next_ >= files_.size()) return std::nullopt;
  const fs::path& file = files_[next_++];
  return NamedImage{file.filename().string(), file.string(), ReadBgrImage(file)};
}

std::vector<std::string> CameraFolders(const fs::path& folder) {
  RequireFolder(folder);
  std::vector<std::string> cameras;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_directory()) cameras.push_back(entry.path().filename().string());
  }
  std::sort(cameras.begin(), cameras.end());
  if (cameras.empty()) {
    throw InputError(folder.string() + ": expected one subfolder of images per camera, found none");
  }
  return cameras;
}

FolderFrameSetSource::FolderFrameSetSource(fs::path folder)
    : folder_(std::move(folder)), cameras_(CameraFolders(folder_)) {
  std::set<std::string> views;
  for (const std::string& camera : cameras_) {
    const std::vector<fs::path> files = ImageFiles(folder_ / camera);
    if (files.empty()) {
      throw InputError((folder_ / camera).string() + ": no images for camera '" + camera + "'");
    }
    for (const fs::path& file : files) views.insert(file.filename().string());
  }
  views_.assign(views.begin(), views.end());
}

std::optional<NamedFrameSet> FolderFrameSetSource::Next() {
  if (next_ >= views_.size()) return std::nullopt;
  NamedFrameSet set;
  set.name = views_[next_++];
  for (const std::string& camera : cameras_) {
    const fs::path file = folder_ / camera / set.name;
    set.sources.push_back(file.string());
    set.images.push_back(fs::exists(file) ? ReadBgrImage(file) : cv::Mat());
  }
  return set;
}

}  // namespace shapesense
