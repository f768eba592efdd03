// `shapesense calibrate background`: each camera's background as the median of
// frames of the empty scene.
#include "clients/tools/calibrate/calibrate_command.h"
#include "libs/calibration/background.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/progress.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

std::vector<cv::Mat> ReadFrames(ImageSource& source, bool progress) {
  std::vector<cv::Mat> frames;
  ProgressBar bar("reading " + source.Describe(), progress);
  while (std::optional<NamedImage> frame = source.Next()) {
    if (!frames.empty() && frame->image.size() != frames[0].size()) {
      throw InputError(frame->source + ": image is " + std::to_string(frame->image.cols) + "x" +
                       std::to_string(frame->image.rows) + ", the camera's first frame was " +
                       std::to_string(frames[0].cols) + "x" + std::to_string(frames[0].rows));
    }
    frames.push_back(frame->image);
    bar.Update(static_cast<double>(frames.size()) / source.Count(), frame->name);
  }
  return frames;
}

// The camera's background; `frame_count` is set to the frames it came from.
cv::Mat CameraBackground(const fs::path& folder, const std::string& camera, bool progress,
                         std::ostream& log, int* frame_count) {
  FolderImageSource source(folder);
  const std::vector<cv::Mat> frames = ReadFrames(source, progress);
  *frame_count = static_cast<int>(frames.size());
  log << "camera " << camera << ": median of " << frames.size() << " frames\n";
  if (frames.size() < 3) {
    log << "camera " << camera << ": warning: a median of fewer than 3 frames removes nothing "
        << "that passes through the view\n";
  }
  ProgressBar bar("median " + camera, progress);
  return MedianImage(
      frames, [&bar](double fraction, const std::string& stage) { bar.Update(fraction, stage); });
}

}  // namespace

BackgroundReport RunCalibrateBackground(const BackgroundArgs& args, std::ostream& log) {
  BackgroundReport report;
  report.cameras = CameraFolders(args.frames);
  std::vector<cv::Mat> backgrounds;  // all computed before any is written
  for (const std::string& camera : report.cameras) {
    int frames = 0;
    backgrounds.push_back(
        CameraBackground(args.frames / camera, camera, args.progress, log, &frames));
    report.frames.push_back(frames);
  }
  fs::create_directories(args.out);
  for (size_t c = 0; c < report.cameras.size(); ++c) {
    WritePng(args.out / (report.cameras[c] + ".png"), backgrounds[c]);
  }
  log << "wrote " << report.cameras.size() << " backgrounds into " << args.out.string() << '\n';
  return report;
}

}  // namespace shapesense
