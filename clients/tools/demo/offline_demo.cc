#include "clients/tools/demo/offline_demo.h"

#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "clients/tools/offline_command.h"
#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "runtime/dataset.h"
#include "runtime/file_io.h"
#include "runtime/progress.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

constexpr double kBodyLength = 150.0;  // mm
constexpr double kRadius = 3.0;        // mm

std::vector<TapeBand> DemoTapes() {
  return {TapeBand{40.0, 4.0, {30, 30, 200}}, TapeBand{85.0, 4.0, {30, 30, 200}},
          TapeBand{125.0, 4.0, {30, 30, 200}}};
}

// Frame i of the demo: the first half bends an arc from straight to 150°
// while its bending plane turns; the second half runs S-curves.
TubeScene DemoScene(const Rig& rig, int i, int frames) {
  const double t = frames > 1 ? static_cast<double>(i) / (frames - 1) : 0.0;
  const double plane = 2.0 * std::numbers::pi * 0.35 * t;
  const Vec3 bend(std::cos(plane), std::sin(plane), 0.0);
  TubeScene scene;
  scene.radius = kRadius;
  scene.tapes = DemoTapes();
  const double degree = std::numbers::pi / 180.0;
  if (t <= 0.5) {
    scene.centerline = ArcCenterline(rig.base_point, Vec3::UnitZ(), bend, 10.0, kBodyLength - 10.0,
                                     300.0 * degree * t);
  } else {
    scene.centerline = SCurveCenterline(rig.base_point, Vec3::UnitZ(), bend, kBodyLength / 2,
                                        (60.0 + 100.0 * (t - 0.5)) * degree, 0.6 * (t - 0.5));
  }
  return scene;
}

nlohmann::json TruthToJson(const std::string& frame, const GroundTruth& truth) {
  auto points = [](const auto& list) {
    nlohmann::json out = nlohmann::json::array();
    for (const Vec3& p : list) out.push_back({p.x(), p.y(), p.z()});
    return out;
  };
  return {{"frame", frame},
          {"centerline", points(truth.centerline)},
          {"tip", {truth.tip.x(), truth.tip.y(), truth.tip.z()}},
          {"markers", points(truth.markers)},
          {"arc_length", truth.length}};
}

// Renders the sequence into out/dataset; returns the truth per frame.
std::map<std::string, GroundTruth> RenderDataset(const OfflineDemoArgs& args, const Rig& rig,
                                                 const fs::path& root) {
  const RenderOptions render;
  const SceneRenderer renderer(rig);
  std::map<std::string, GroundTruth> truths;
  std::string truth_lines;
  ProgressBar bar("rendering", args.progress);
  for (int i = 0; i < args.frames; ++i) {
    const TubeScene scene = DemoScene(rig, i, args.frames);
    const std::vector<RenderedView> views =
        renderer.Render(scene, render, args.seed + static_cast<uint32_t>(i));
    std::vector<cv::Mat> images;
    images.reserve(views.size());
    for (const RenderedView& view : views) images.push_back(view.image);
    if (i == 0) {
      std::vector<cv::Mat> backgrounds;
      backgrounds.reserve(views.size());
      for (const RenderedView& view : views) backgrounds.push_back(view.background);
      WriteDatasetHeader(root, rig, backgrounds);
    }
    WriteFrame(root, rig, FrameName(i), images);
    truths[FrameName(i)] = TruthOf(scene);
    truth_lines += TruthToJson(FrameName(i), truths[FrameName(i)]).dump() + "\n";
    bar.Update(static_cast<double>(i + 1) / args.frames);
  }
  bar.Finish();
  WriteFileAtomically(root / "truth.jsonl", truth_lines);
  return truths;
}

void PrintFrameRow(std::ostream& log, const std::string& frame, const FrameResult& result,
                   const ShapeError* error) {
  log << std::setw(7) << frame;
  if (error == nullptr) {
    log << "  not measured: " << result.shape.error << '\n';
    return;
  }
  log << std::fixed << std::setprecision(3) << std::setw(10) << error->centerline_rms
      << std::setw(10) << error->coverage_rms << std::setw(9) << error->tip << std::setw(9)
      << error->marker_max << std::setw(6) << error->markers_found << "/" << error->markers_expected
      << std::setw(10) << result.times.silhouette_ms << std::setw(9) << result.times.carving_ms
      << std::setw(9) << result.times.shape_ms << '\n';
}

nlohmann::json SummaryToJson(const OfflineDemoReport& report) {
  const ShapeErrorSummary& a = report.accuracy;
  return {{"frames", a.frames},
          {"failed", a.failed},
          {"centerline_rms_mm", {{"mean", a.mean.centerline_rms}, {"max", a.max.centerline_rms}}},
          {"coverage_rms_mm", {{"mean", a.mean.coverage_rms}, {"max", a.max.coverage_rms}}},
          {"tip_error_mm", {{"mean", a.mean.tip}, {"max", a.max.tip}}},
          {"marker_error_mm", {{"rms_mean", a.mean.marker_rms}, {"max", a.max.marker_max}}},
          {"markers_found", a.mean.markers_found},
          {"markers_expected", a.mean.markers_expected},
          {"stage_ms",
           {{"silhouette", report.mean_times.silhouette_ms},
            {"carving", report.mean_times.carving_ms},
            {"shape", report.mean_times.shape_ms}}},
          {"table_build_s", report.table_build_s}};
}

void PrintSummary(std::ostream& log, const OfflineDemoReport& report) {
  const ShapeErrorSummary& a = report.accuracy;
  log << std::fixed << std::setprecision(3) << "\naccuracy over " << a.frames - a.failed << " of "
      << a.frames << " frames (mean / max):\n"
      << "  centreline RMS   " << a.mean.centerline_rms << " / " << a.max.centerline_rms << " mm\n"
      << "  coverage RMS     " << a.mean.coverage_rms << " / " << a.max.coverage_rms << " mm\n"
      << "  tip              " << a.mean.tip << " / " << a.max.tip << " mm\n"
      << "  tape centres     " << a.mean.marker_rms << " / " << a.max.marker_max << " mm ("
      << a.mean.markers_found << " of " << a.mean.markers_expected << " found)\n"
      << "stage times (mean): silhouettes " << report.mean_times.silhouette_ms << " ms, carving "
      << report.mean_times.carving_ms << " ms, shape " << report.mean_times.shape_ms << " ms"
      << " (lookup table built once in " << std::setprecision(1) << report.table_build_s << " s)\n";
}

}  // namespace

OfflineDemoReport RunOfflineDemo(const OfflineDemoArgs& args, std::ostream& log) {
  if (args.frames < 1) throw InputError("--frames: expected at least 1");
  SyntheticRigOptions rig_options;
  rig_options.seed = args.seed;
  const Rig rig = MakeSyntheticRig(rig_options);
  const fs::path dataset = args.out / "dataset";
  log << "rendering " << args.frames << " frames of a virtual " << rig.cameras.size()
      << "-camera rig into " << dataset.string() << '\n';
  const std::map<std::string, GroundTruth> truths = RenderDataset(args, rig, dataset);

  OfflineArgs offline{dataset, args.out / "shapes.jsonl", args.voxel_size, {}, {}, args.progress};
  fs::create_directories(args.out / "overlays");
  std::vector<ShapeError> errors;
  int failed = 0;
  log << "  frame  cl_rms_mm  cover_mm  tip_mm  mark_mm  tapes  silh_ms  carv_ms  shape_ms\n";
  const auto observe = [&](const std::string& frame, const std::vector<cv::Mat>& images,
                           const FrameResult& result) {
    const GroundTruth& truth = truths.at(frame);
    if (!result.shape.valid) {
      ++failed;
      PrintFrameRow(log, frame, result, nullptr);
    } else {
      errors.push_back(CompareShape(result.shape, truth));
      PrintFrameRow(log, frame, result, &errors.back());
    }
    if (!images.empty()) {
      WritePng(args.out / "overlays" / (frame + ".png"),
               MakeFrameOverlay(rig, images, result, &truth.centerline));
    }
  };
  const OfflineSummary offline_summary = RunOffline(offline, log, observe);
  OfflineDemoReport report{Summarize(errors, failed), offline_summary.mean_times,
                           offline_summary.table_build_s};
  PrintSummary(log, report);
  WriteFileAtomically(args.out / "report.json", SummaryToJson(report).dump(2) + "\n");
  log << "wrote " << (args.out / "shapes.jsonl").string() << ", "
      << (args.out / "overlays").string() << "/*.png, " << (args.out / "report.json").string()
      << '\n';
  return report;
}

}  // namespace shapesense
