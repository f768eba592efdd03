#include "clients/tools/offline_command.h"

#include <chrono>
#include <fstream>
#include <iomanip>

#include "libs/core/error.h"
#include "libs/viz/overlay.h"
#include "runtime/config_file.h"
#include "runtime/dataset.h"
#include "runtime/file_io.h"
#include "runtime/progress.h"
#include "runtime/provenance.h"
#include "runtime/shape_json.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

PipelineOptions LoadPipelineOptions(const OfflineArgs& args) {
  PipelineOptions options = LoadOptionsFile<PipelineOptions>(args.config);
  if (args.voxel_size) {
    options.carving.voxel_size = *args.voxel_size;
    if (const std::string error = options.Validate(); !error.empty()) {
      throw InputError("--voxel-size: " + error);
    }
  }
  return options;
}

std::ofstream OpenOutput(const fs::path& path) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw InputError(path.string() + ": cannot be opened for writing");
  return out;
}

// Beside the output: results.jsonl -> results.config.yaml.
fs::path EffectiveConfigPath(const fs::path& out) {
  fs::path path = out;
  return path.replace_extension(".config.yaml");
}

// Builds the carving lookup table with a progress bar.
SensingPipeline MakePipeline(const Dataset& dataset, const PipelineOptions& options,
                             bool progress) {
  ProgressBar bar("lookup table", progress);
  return SensingPipeline(dataset.rig, options, dataset.backgrounds,
                         [&bar](double fraction) { bar.Update(fraction); });
}

void AccumulateTimes(const StageTimes& times, StageTimes* sum) {
  sum->silhouette_ms += times.silhouette_ms;
  sum->carving_ms += times.carving_ms;
  sum->shape_ms += times.shape_ms;
}

}  // namespace

cv::Mat MakeFrameOverlay(const Rig& rig, const std::vector<cv::Mat>& images,
                         const FrameResult& result, const Polyline* truth) {
  std::vector<cv::Mat> views;
  for (size_t i = 0; i < rig.cameras.size() && i < images.size(); ++i) {
    views.push_back(DrawCameraOverlay(images[i], result.silhouettes.at(i), rig.cameras[i],
                                      result.shape, truth));
  }
  const cv::Mat cameras = TileImages(views, 3);
  const cv::Mat orthogonal =
      DrawOrthogonalViews(result.cloud, result.shape, truth, cameras.cols / 3);
  cv::Mat picture;
  cv::vconcat(cameras, orthogonal, picture);
  return picture;
}

OfflineSummary RunOffline(const OfflineArgs& args, std::ostream& log,
                          const FrameObserver& observer) {
  const PipelineOptions options = LoadPipelineOptions(args);
  const Dataset dataset = OpenDataset(args.dataset);
  log << "dataset " << args.dataset.string() << ": " << dataset.rig.cameras.size() << " cameras, "
      << dataset.frames.size() << " frames, voxel size " << options.carving.voxel_size << " mm\n";
  OfflineSummary summary;
  const auto build_start = Clock::now();
  const SensingPipeline pipeline = MakePipeline(dataset, options, args.progress);
  summary.table_build_s = SecondsSince(build_start);
  std::ofstream out = OpenOutput(args.out);
  WriteEffectiveConfig(
      EffectiveConfigPath(args.out),
      "shapesense offline on " + args.dataset.string() + " -> " + args.out.string(),
      OptionsToDocumentedYaml(options));
  if (!args.overlays.empty()) fs::create_directories(args.overlays);

  ProgressBar bar("frames", args.progress);
  FrameResult result;
  for (const std::string& frame : dataset.frames) {
    const auto load_start = Clock::now();
    std::vector<cv::Mat> images;
    try {
      images = LoadFrame(dataset, frame);
    } catch (const InputError& e) {
      out << FrameErrorToJson(frame, e.what()).dump() << '\n' << std::flush;
      log << "frame " << frame << ": " << e.what() << '\n';
      ++summary.frames;
      if (observer) observer(frame, {}, FrameResult{});
      continue;
    }
    const double load_ms = 1e3 * SecondsSince(load_start);
    pipeline.Process(images, &result);
    out << ShapeToJson(frame, result.shape, result.times, load_ms).dump() << '\n' << std::flush;
    ++summary.frames;
    if (result.shape.valid) {
      ++summary.measured;
      AccumulateTimes(result.times, &summary.mean_times);
    } else {
      log << "frame " << frame << ": not measured: " << result.shape.error << '\n';
    }
    if (!args.overlays.empty()) {
      WritePng(args.overlays / (frame + ".png"),
               MakeFrameOverlay(dataset.rig, images, result, nullptr));
    }
    if (observer) observer(frame, images, result);
    bar.Update(
        static_cast<double>(summary.frames) / static_cast<double>(dataset.frames.size()),
        "frame " + std::to_string(summary.frames) + "/" + std::to_string(dataset.frames.size()));
  }
  bar.Finish();
  if (summary.measured > 0) {
    const double n = summary.measured;
    summary.mean_times = {summary.mean_times.silhouette_ms / n, summary.mean_times.carving_ms / n,
                          summary.mean_times.shape_ms / n};
  }
  return summary;
}

void AddOfflineCommand(CLI::App& app) {
  auto args = std::make_shared<OfflineArgs>();
  auto voxel_size = std::make_shared<double>(0.0);
  CLI::App* command = app.add_subcommand(
      "offline", "Measure the shape in every frame of an image-folder dataset (docs/dataset.md)");
  command->add_option("--dataset", args->dataset, "dataset folder (rig.yaml, background/, frames/)")
      ->required();
  command->add_option("--out", args->out, "output, one JSON object per frame (.jsonl)")->required();
  CLI::Option* voxel =
      command->add_option("--voxel-size", *voxel_size, "voxel edge, mm (default 1)");
  command->add_option("--config", args->config, "pipeline options YAML (config/pipeline.yaml)");
  command->add_option("--overlays", args->overlays,
                      "write an overlay PNG per frame into this folder");
  command->callback([args, voxel_size, voxel] {
    if (voxel->count() > 0) args->voxel_size = *voxel_size;
    const OfflineSummary summary = RunOffline(*args, std::cerr);
    std::cerr << std::fixed << std::setprecision(3) << "measured " << summary.measured << " of "
              << summary.frames << " frames; mean ms: silhouette "
              << summary.mean_times.silhouette_ms << ", carving " << summary.mean_times.carving_ms
              << ", shape " << summary.mean_times.shape_ms << "; wrote " << args->out.string()
              << '\n';
  });
}

}  // namespace shapesense
