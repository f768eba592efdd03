// `shapesense calibrate intrinsics`: one camera's model from views of a board.
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "clients/tools/calibrate/calibrate_command.h"
#include "libs/calibration/calibration_drawing.h"
#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/progress.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

struct Detections {
  std::vector<BoardObservation> views;
  std::vector<std::string> names;
  std::vector<cv::Mat> images;            // per view, kept only for overlays
  std::vector<NamedImage> without_board;  // image empty unless kept for overlays
  cv::Size size;
  int total = 0;
};

void CheckSameSize(const NamedImage& image, Detections* found) {
  if (found->size.empty()) {
    found->size = image.image.size();
  } else if (image.image.size() != found->size) {
    throw InputError(image.source + ": image is " + std::to_string(image.image.cols) + "x" +
                     std::to_string(image.image.rows) + ", the first was " +
                     std::to_string(found->size.width) + "x" + std::to_string(found->size.height) +
                     "; the views must all come from one camera");
  }
}

Detections DetectViews(ImageSource& source, const CalibrationBoard& board, bool keep_images,
                       bool progress, std::ostream& log) {
  Detections found;
  ProgressBar bar("finding the board", progress);
  while (std::optional<NamedImage> image = source.Next()) {
    CheckSameSize(*image, &found);
    ++found.total;
    bar.Update(static_cast<double>(found.total) / source.Count(), image->name);
    std::optional<BoardObservation> seen = board.Detect(image->image);
    if (!seen) {
      log << image->name << ": board not found\n";
      if (!keep_images) image->image.release();
      found.without_board.push_back(std::move(*image));
      continue;
    }
    found.views.push_back(std::move(*seen));
    found.names.push_back(image->name);
    if (keep_images) found.images.push_back(image->image);
  }
  bar.Finish();
  if (found.views.empty()) {
    throw InputError(source.Describe() + ": no " + board.Describe() + " found in any of its " +
                     std::to_string(found.total) +
                     " images; check --pattern, and --cols/--rows, which count inner corners "
                     "(9x6 for a board of 10x7 squares)");
  }
  return found;
}

IntrinsicsResult Calibrate(const ImageSource& source, const Detections& found,
                           const CalibrationBoard& board, const IntrinsicsOptions& options,
                           bool progress) {
  ProgressBar bar("calibrating", progress);
  try {
    return CalibrateIntrinsics(
        found.views, board, found.size.width, found.size.height, options,
        [&bar](double fraction, const std::string& stage) { bar.Update(fraction, stage); });
  } catch (const InputError& e) {
    throw InputError(source.Describe() + ": " + e.what());
  }
}

void LogViews(const Detections& found, const IntrinsicsResult& result, std::ostream& log) {
  log << std::left << std::setw(28) << "view" << std::setw(9) << "corners"
      << "RMS px\n";
  for (size_t i = 0; i < found.views.size(); ++i) {
    const ViewFit& fit = result.views[i];
    log << std::left << std::setw(28) << found.names[i] << std::setw(9) << found.views[i].size()
        << std::fixed << std::setprecision(3) << fit.rms_px
        << (fit.used ? "" : "  left out: spoils the fit") << '\n';
  }
}

void LogCamera(const IntrinsicsResult& result, int total_images, std::ostream& log) {
  const Camera& c = result.camera;
  log << std::fixed << std::setprecision(3) << "fx " << c.camera_matrix(0, 0) << "  fy "
      << c.camera_matrix(1, 1) << "  cx " << c.camera_matrix(0, 2) << "  cy "
      << c.camera_matrix(1, 2) << " px; distortion k1 k2 p1 p2 k3 " << std::setprecision(5)
      << c.distortion[0] << ' ' << c.distortion[1] << ' ' << c.distortion[2] << ' '
      << c.distortion[3] << ' ' << c.distortion[4] << '\n'
      << std::setprecision(3) << "reprojection error " << result.rms_px << " px RMS over "
      << result.UsedViews() << " views (of " << total_images << " images)\n";
}

std::string OverlayName(const std::string& view) { return fs::path(view).stem().string() + ".png"; }

void WriteOverlays(const fs::path& folder, const Detections& found,
                   const IntrinsicsResult& result) {
  fs::create_directories(folder);
  for (size_t i = 0; i < found.views.size(); ++i) {
    const ViewFit& fit = result.views[i];
    char caption[160];
    std::snprintf(caption, sizeof(caption), "%s: %zu corners, RMS %.3f px", found.names[i].c_str(),
                  found.views[i].size(), fit.rms_px);
    WritePng(
        folder / OverlayName(found.names[i]),
        DrawCornerOverlay(found.images[i], found.views[i], fit.reprojected, caption, !fit.used));
  }
  for (const NamedImage& image : found.without_board) {
    WritePng(folder / OverlayName(image.name),
             DrawCornerOverlay(image.image, {}, {}, image.name + ": board not found", false));
  }
}

void CreateParentFolder(const fs::path& path) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
}

}  // namespace

std::string FormatCalibratedCameraYaml(const Camera& camera, double reprojection_error_px) {
  std::string text = FormatCameraYaml(camera);
  if (!text.empty() && text.back() != '\n') text += '\n';
  std::ostringstream error;
  error << std::setprecision(9) << reprojection_error_px;
  return text + "reprojection_error: " + error.str() + "\n";
}

IntrinsicsReport RunCalibrateIntrinsicsFrom(ImageSource& source, const IntrinsicsArgs& args,
                                            std::ostream& log) {
  const CalibrationBoard board(args.board);
  if (const std::string error = args.options.Validate(); !error.empty()) {
    throw InputError("intrinsics options: " + error);
  }
  log << source.Describe() << ": " << source.Count() << " images; looking for a "
      << board.Describe() << '\n';
  Detections found = DetectViews(source, board, !args.overlays.empty(), args.progress, log);
  IntrinsicsReport report;
  report.result = Calibrate(source, found, board, args.options, args.progress);
  report.result.camera.name = args.name.empty() ? args.out.stem().string() : args.name;
  LogViews(found, report.result, log);
  LogCamera(report.result, found.total, log);
  CreateParentFolder(args.out);
  WriteFileAtomically(args.out,
                      FormatCalibratedCameraYaml(report.result.camera, report.result.rms_px));
  log << "wrote " << args.out.string() << '\n';
  if (!args.overlays.empty()) WriteOverlays(args.overlays, found, report.result);
  report.view_names = found.names;
  for (const NamedImage& image : found.without_board) report.without_board.push_back(image.name);
  return report;
}

IntrinsicsReport RunCalibrateIntrinsics(const IntrinsicsArgs& args, std::ostream& log) {
  const CalibrationBoard board(args.board);  // a bad board fails before any image is read
  FolderImageSource source(args.images);
  return RunCalibrateIntrinsicsFrom(source, args, log);
}

}  // namespace shapesense
