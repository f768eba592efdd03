// `shapesense calibrate extrinsics`: the rig file from synchronised views of a
// board and each camera's intrinsics.
#include <cstdio>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "clients/tools/calibrate/calibrate_command.h"
#include "clients/tools/calibrate/point_csv.h"
#include "libs/calibration/calibration_drawing.h"
#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/progress.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// "name=file" -> the camera's intrinsics, named.
std::map<std::string, Camera> LoadIntrinsics(const std::vector<std::string>& specs) {
  std::map<std::string, Camera> cameras;
  for (const std::string& spec : specs) {
    const size_t equals = spec.find('=');
    if (equals == std::string::npos || equals == 0 || equals + 1 == spec.size()) {
      throw InputError("--intrinsics: expected CAMERA=FILE (e.g. cam0=cam0.yaml), got '" + spec +
                       "'");
    }
    const std::string name = spec.substr(0, equals);
    const fs::path file = spec.substr(equals + 1);
    Camera camera = ParseCameraYaml(ReadTextFile(file), file.string());
    camera.name = name;
    if (!cameras.emplace(name, camera).second) {
      throw InputError("--intrinsics: camera '" + name + "' is given twice");
    }
  }
  return cameras;
}

// The cameras in the order of the source's camera folders.
std::vector<Camera> MatchCameras(const FrameSetSource& source,
                                 const std::map<std::string, Camera>& intrinsics) {
  std::vector<Camera> cameras;
  for (const std::string& name : source.CameraNames()) {
    const auto found = intrinsics.find(name);
    if (found == intrinsics.end()) {
      std::ostringstream message;
      message << (fs::path(source.Describe()) / name).string() << ": camera '" << name
              << "' has no intrinsics; give --intrinsics " << name << "=FILE";
      throw InputError(message.str());
    }
    cameras.push_back(found->second);
  }
  const std::set<std::string> folders(source.CameraNames().begin(), source.CameraNames().end());
  for (const auto& [name, camera] : intrinsics) {
    if (!folders.contains(name)) {
      throw InputError("--intrinsics " + name + ": no folder " +
                       (fs::path(source.Describe()) / name).string() + " of its views");
    }
  }
  return cameras;
}

Rig RigOutline(const ExtrinsicsArgs& args) {
  Rig rig;
  rig.workspace_min = args.workspace_min;
  rig.workspace_max = args.workspace_max;
  rig.base_point = args.base_point;
  if (!(rig.workspace_min.array() < rig.workspace_max.array()).all()) {
    throw InputError("--workspace-min, --workspace-max: expected min below max on every axis");
  }
  if (!rig.workspace_min.allFinite() || !rig.workspace_max.allFinite() ||
      !rig.base_point.allFinite()) {
    throw InputError("--workspace-min, --workspace-max, --base-point: expected finite numbers");
  }
  return rig;
}

std::vector<AnchorPoint> LoadAnchorPoints(const fs::path& file) {
  std::vector<AnchorPoint> anchors;
  if (file.empty()) return anchors;
  for (const NamedPoint& point : ParsePointCsv(ReadTextFile(file), file.string())) {
    size_t used = 0;
    int corner = -1;
    try {
      corner = std::stoi(point.name, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (point.name.empty() || used != point.name.size()) {
      throw InputError(file.string() + ": expected lines corner,x,y,z with a corner number, got '" +
                       point.name + "'");
    }
    anchors.push_back({corner, point.position});
  }
  return anchors;
}

struct Views {
  ExtrinsicsInput input;
  std::vector<std::vector<cv::Mat>> images;  // [camera][view], kept only for overlays
  std::vector<int> found;                    // per camera
  std::vector<int> present;                  // per camera: views with a picture
};

void CheckImageSize(const Camera& camera, const cv::Mat& image, const std::string& source) {
  if (image.cols != camera.width || image.rows != camera.height) {
    throw InputError(source + ": image is " + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + " but camera '" + camera.name +
                     "' has intrinsics for " + std::to_string(camera.width) + "x" +
                     std::to_string(camera.height));
  }
}

void DetectInFrameSet(const NamedFrameSet& set, const CalibrationBoard& board, bool keep_images,
                      std::ostream& log, Views* views) {
  views->input.view_names.push_back(set.name);
  for (size_t c = 0; c < views->input.cameras.size(); ++c) {
    const cv::Mat& image = set.images[c];
    std::optional<BoardObservation> seen;
    if (image.empty()) {
      log << set.sources[c] << ": missing; camera '" << views->input.cameras[c].name
          << "' has no picture of view " << set.name << '\n';
    } else {
      CheckImageSize(views->input.cameras[c], image, set.sources[c]);
      ++views->present[c];
      seen = board.Detect(image);
    }
    views->found[c] += seen ? 1 : 0;
    views->input.observations[c].push_back(std::move(seen));
    views->images[c].push_back(keep_images ? image : cv::Mat());
  }
}

Views DetectViews(FrameSetSource& source, std::vector<Camera> cameras,
                  const CalibrationBoard& board, bool keep_images, bool progress,
                  std::ostream& log) {
  Views views;
  const size_t n = cameras.size();
  views.input.cameras = std::move(cameras);
  views.input.observations.resize(n);
  views.images.resize(n);
  views.found.assign(n, 0);
  views.present.assign(n, 0);
  ProgressBar bar("finding the board", progress);
  while (std::optional<NamedFrameSet> set = source.Next()) {
    DetectInFrameSet(*set, board, keep_images, log, &views);
    bar.Update(static_cast<double>(views.input.view_names.size()) / source.Count(), set->name);
  }
  bar.Finish();
  for (size_t c = 0; c < n; ++c) {
    const std::string& name = views.input.cameras[c].name;
    log << "camera " << name << ": board found in " << views.found[c] << " of " << views.present[c]
        << " views\n";
    if (views.found[c] == 0) {
      throw InputError((fs::path(source.Describe()) / name).string() + ": camera '" + name +
                       "' never sees the board: no " + board.Describe() + " found in any of its " +
                       std::to_string(views.present[c]) + " images");
    }
  }
  return views;
}

ExtrinsicsResult Calibrate(const FrameSetSource& source, const Views& views,
                           const CalibrationBoard& board, const ExtrinsicsOptions& options,
                           bool progress) {
  ProgressBar bar("bundle adjustment", progress);
  try {
    return CalibrateExtrinsics(
        views.input, board, options,
        [&bar](double fraction, const std::string& stage) { bar.Update(fraction, stage); });
  } catch (const InputError& e) {
    throw InputError(source.Describe() + ": " + e.what());
  }
}

void LogResult(const Views& views, const ExtrinsicsResult& result, std::ostream& log) {
  log << std::fixed << std::setprecision(3);
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    const Vec3 centre = result.cameras[c].Center();
    log << "camera " << result.cameras[c].name << ": reprojection error " << result.camera_rms_px[c]
        << " px RMS; centre (" << centre.x() << ", " << centre.y() << ", " << centre.z()
        << ") mm\n";
    for (size_t v = 0; v < views.input.view_names.size(); ++v) {
      const auto& fit = result.fits[c][v];
      if (fit && !fit->used) {
        log << "  view " << views.input.view_names[v] << ": RMS " << fit->rms_px
            << " px, left out: spoils the fit\n";
      }
    }
  }
  log << "reprojection error " << result.rms_px
      << " px RMS over all cameras; solver: " << result.solver_report << '\n';
}

std::string RigYamlWithErrors(const Rig& rig, const ExtrinsicsResult& result) {
  std::ostringstream comment;
  comment << std::fixed << std::setprecision(4) << "# reprojection error, px RMS:";
  for (size_t c = 0; c < rig.cameras.size(); ++c) {
    comment << ' ' << rig.cameras[c].name << ' ' << result.camera_rms_px[c];
  }
  std::string text = FormatRigYaml(rig);
  if (!text.empty() && text.back() != '\n') text += '\n';
  return text + comment.str() + '\n';
}

std::string Caption(const std::string& camera, const std::string& view,
                    const std::optional<ObservationFit>& fit) {
  char text[200];
  if (fit) {
    std::snprintf(text, sizeof(text), "%s %s: RMS %.3f px", camera.c_str(), view.c_str(),
                  fit->rms_px);
  } else {
    std::snprintf(text, sizeof(text), "%s %s: board not found", camera.c_str(), view.c_str());
  }
  return text;
}

void WriteOverlays(const fs::path& folder, const Views& views, const ExtrinsicsResult& result) {
  for (size_t c = 0; c < result.cameras.size(); ++c) {
    const fs::path camera_folder = folder / result.cameras[c].name;
    fs::create_directories(camera_folder);
    for (size_t v = 0; v < views.input.view_names.size(); ++v) {
      if (views.images[c][v].empty()) continue;
      const std::string& view = views.input.view_names[v];
      const auto& fit = result.fits[c][v];
      WritePng(camera_folder / (fs::path(view).stem().string() + ".png"),
               DrawCornerOverlay(views.images[c][v],
                                 views.input.observations[c][v].value_or(BoardObservation{}),
                                 fit ? fit->reprojected : std::vector<Vec2>{},
                                 Caption(result.cameras[c].name, view, fit), fit && !fit->used));
    }
  }
}

void LogWorldFrame(const ExtrinsicsArgs& args, const Views& views, std::ostream& log) {
  const size_t anchor = static_cast<size_t>(args.options.anchor_view);
  if (anchor >= views.input.view_names.size()) return;  // the library names the problem
  const std::string& view = views.input.view_names[anchor];
  if (args.anchor_points.empty()) {
    log << "world frame: the board of view " << view
        << " (origin at its corner 0, z out of its printed side)\n";
  } else {
    log << "world frame: that of " << args.anchor_points.string() << " (corners of view " << view
        << ")\n";
  }
}

}  // namespace

ExtrinsicsReport RunCalibrateExtrinsicsFrom(FrameSetSource& source, const ExtrinsicsArgs& args,
                                            std::ostream& log) {
  const CalibrationBoard board(args.board);
  if (const std::string error = args.options.Validate(); !error.empty()) {
    throw InputError("extrinsics options: " + error);
  }
  ExtrinsicsReport report;
  report.rig = RigOutline(args);
  std::vector<Camera> cameras = MatchCameras(source, LoadIntrinsics(args.intrinsics));
  Views views =
      DetectViews(source, std::move(cameras), board, !args.overlays.empty(), args.progress, log);
  views.input.anchor_points = LoadAnchorPoints(args.anchor_points);
  LogWorldFrame(args, views, log);
  report.result = Calibrate(source, views, board, args.options, args.progress);
  LogResult(views, report.result, log);
  report.rig.cameras = report.result.cameras;
  if (const std::string error = report.rig.Validate(); !error.empty()) {
    throw InputError("extrinsics: the calibrated rig is not valid: " + error);
  }
  if (args.out.has_parent_path()) fs::create_directories(args.out.parent_path());
  WriteFileAtomically(args.out, RigYamlWithErrors(report.rig, report.result));
  log << "wrote " << args.out.string() << '\n';
  if (!args.overlays.empty()) WriteOverlays(args.overlays, views, report.result);
  report.view_names = views.input.view_names;
  return report;
}

ExtrinsicsReport RunCalibrateExtrinsics(const ExtrinsicsArgs& args, std::ostream& log) {
  const CalibrationBoard board(args.board);  // a bad board fails before any image is read
  FolderFrameSetSource source(args.views);
  return RunCalibrateExtrinsicsFrom(source, args, log);
}

}  // namespace shapesense
