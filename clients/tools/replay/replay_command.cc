#include "clients/tools/replay/replay_command.h"

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <regex>

#include "libs/core/error.h"
#include "runtime/dataset.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/stage_times.h"
#include "runtime/lcm/wire_check.h"
#include "runtime/progress.h"
#include "runtime/shape_json.h"
#include "services/carving/carving_service.h"
#include "services/shape/shape_service.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// The "frame" of a JSON line: the trigger sequence as the dataset layout
// names frames, or "t<trigger µs>" for a set matched by time.
std::string FrameNameOf(int64_t trigger_seq, int64_t trigger_utime) {
  if (trigger_seq >= 0 && trigger_seq <= INT32_MAX) return FrameName(static_cast<int>(trigger_seq));
  return trigger_seq >= 0 ? std::to_string(trigger_seq) : "t" + std::to_string(trigger_utime);
}

double StageMs(const shape_t& shape, const char* stage) {
  const stage_time_t* time = FindStageTime(shape.stage_times, stage);
  return time == nullptr ? 0.0 : static_cast<double>(time->duration_us) * 1e-3;
}

// Where the shapes go: JSON lines and/or an LCM log, both opened before any work.
class ShapeWriter {
 public:
  explicit ShapeWriter(const ReplayArgs& args) {
    if (args.out.empty() && args.out_log.empty()) {
      throw InputError(
          "replay: expected an output (--out shapes.jsonl or --out-log shapes.lcmlog)");
    }
    if (!args.out.empty()) {
      if (args.out.has_parent_path()) fs::create_directories(args.out.parent_path());
      json_.open(args.out, std::ios::trunc);
      if (!json_) throw InputError(args.out.string() + ": cannot be opened for writing");
    }
    if (!args.out_log.empty()) {
      if (args.out_log.has_parent_path()) fs::create_directories(args.out_log.parent_path());
      log_ = std::make_unique<lcm::LogFile>(args.out_log.string(), "w");
      if (!log_->good()) throw InputError(args.out_log.string() + ": cannot be opened for writing");
    }
  }

  void Write(const shape_t& shape, const ShapeEstimate& estimate, int64_t timestamp) {
    if (json_.is_open()) {
      const StageTimes times{StageMs(shape, "silhouette"), StageMs(shape, "carving"),
                             StageMs(shape, "shape")};
      nlohmann::json line =
          ShapeToJson(FrameNameOf(shape.trigger_seq, shape.trigger_utime), estimate, times, 0.0);
      line["trigger_seq"] = shape.trigger_seq;
      line["trigger_utime"] = shape.trigger_utime;
      if (shape.has_configuration) {
        line["q"] = {shape.q[0], shape.q[1], shape.q[2], shape.q[3]};
        line["configuration_residual_mm"] = shape.configuration_residual_mm;
      }
      json_ << line.dump() << '\n';
    }
    if (log_) WriteEvent(channels::kShape, shape, timestamp);
  }

  void WriteError(const std::string& frame, const std::string& error) {
    if (json_.is_open()) json_ << FrameErrorToJson(frame, error).dump() << '\n';
  }

 private:
  template <class Message>
  void WriteEvent(const std::string& channel, const Message& message, int64_t timestamp) {
    std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
    message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::LogEvent event{};
    event.timestamp = timestamp;
    event.channel = channel;
    event.datalen = static_cast<int32_t>(bytes.size());
    event.data = bytes.data();
    log_->writeEvent(&event);
  }

  std::ofstream json_;
  std::unique_ptr<lcm::LogFile> log_;
};

// The live services' two stages and the carving service's door, in one loop.
class ReplayPipeline {
 public:
  ReplayPipeline(const CarvingServiceOptions& carving, const ShapeServiceOptions& shape,
                 std::optional<ConfigurationSetup> configuration, RigSetup setup,
                 ShapeWriter& writer, const ReplayObserver& observer, bool progress)
      : carving_stage_(setup.rig, std::move(setup.backgrounds), carving.silhouette, carving.carving,
                       TableProgress(progress)),
        shape_stage_(setup.rig, shape.shape, std::move(configuration)),
        assembler_(CameraNames(setup.rig), carving.assembly),
        writer_(writer),
        observer_(observer) {}

  void OnEvent(const lcm::LogEvent& event, ReplaySummary* summary) {
    image_t image;
    ++summary->images;
    const size_t size = event.datalen > 0 ? static_cast<size_t>(event.datalen) : 0;
    if (!DecodeMessage(event.data, size, &image).empty() || !ValidateImageMessage(image).empty()) {
      ++summary->rejected;
      return;
    }
    AssemblyResult result = assembler_.Add(std::move(image), event.timestamp);
    if (result.outcome == AssemblyOutcome::kCompleted) {
      Process(*result.completed, event.timestamp, summary);
    }
    if (IsRejection(result.outcome)) ++summary->rejected;
  }

  void Finish(ReplaySummary* summary) {
    summary->frame_sets = assembler_.counters().completed;
    // Sets still open at the end of the log are dropped as the live service would, after the
    // timeout.
    summary->dropped_sets =
        assembler_.counters().DroppedSets() + static_cast<int64_t>(assembler_.pending());
  }

 private:
  static ProgressCallback TableProgress(bool progress) {
    auto bar = std::make_shared<ProgressBar>("lookup table", progress);
    return [bar](double fraction) { bar->Update(fraction); };
  }

  void Process(const FrameSet& set, int64_t timestamp, ReplaySummary* summary) {
    if (const std::string error = carving_stage_.Process(set, &carved_); !error.empty()) {
      ++summary->not_carved;
      writer_.WriteError(FrameNameOf(set.trigger_seq, set.trigger_utime), error);
      return;
    }
    // What the live shape service gets from the carving service: the cloud
    // and the compact silhouettes.
    const SilhouetteSet* silhouettes =
        shape_stage_.wants_silhouettes() ? &carved_.compact : nullptr;
    if (!shape_stage_.Process(carved_.message, silhouettes, &shaped_).empty())
      return;  // cannot happen: our own cloud
    shaped_.message.header.seq = shape_seq_++;
    shaped_.message.header.utime = timestamp;
    writer_.Write(shaped_.message, shaped_.estimate, timestamp);
    if (observer_) observer_(shaped_.message);
    if (!shaped_.estimate.valid) return;
    ++summary->measured;
    summary->mean_silhouette_ms += StageMs(shaped_.message, "silhouette");
    summary->mean_carving_ms += StageMs(shaped_.message, "carving");
    summary->mean_shape_ms += StageMs(shaped_.message, "shape");
  }

  CarvingStage carving_stage_;
  ShapeStage shape_stage_;
  FrameSetAssembler assembler_;
  ShapeWriter& writer_;
  const ReplayObserver& observer_;
  CarvingOutput carved_;
  ShapeOutput shaped_;
  int64_t shape_seq_ = 0;
};

// Both configs, with the rig of the carving one (or the command line's) for
// both: replay measures with one rig.
std::pair<CarvingServiceOptions, ShapeServiceOptions> LoadReplayOptions(const ReplayArgs& args) {
  const CarvingServiceOptions carving =
      LoadCarvingServiceOptions({args.config, std::nullopt, args.rig, args.backgrounds, 0.0});
  const ShapeServiceOptions shape =
      LoadShapeServiceOptions({args.shape_config, std::nullopt, fs::path(carving.rig), {}, 0.0});
  return {carving, shape};
}

// Several LCM logs read as one, in the order of their events' times (each
// log is in time order already).
class MergedLogs {
 public:
  // Throws InputError naming a log that cannot be read.
  explicit MergedLogs(const std::vector<fs::path>& paths) {
    if (paths.empty()) throw InputError("replay: expected at least one LCM log");
    for (const fs::path& path : paths) {
      std::error_code error;
      total_size_ += static_cast<double>(fs::file_size(path, error));
      files_.push_back(std::make_unique<lcm::LogFile>(path.string(), "r"));
      if (error || !files_.back()->good()) {
        throw InputError(path.string() + ": cannot be read as an LCM log");
      }
      heads_.push_back(files_.back()->readNextEvent());
    }
  }

  // The earliest event not yet returned, or nullptr at the end; valid until the next call.
  const lcm::LogEvent* Next() {
    if (taken_) heads_[*taken_] = files_[*taken_]->readNextEvent();
    taken_.reset();
    for (size_t i = 0; i < heads_.size(); ++i) {
      if (heads_[i] != nullptr && (!taken_ || heads_[i]->timestamp < heads_[*taken_]->timestamp)) {
        taken_ = i;
      }
    }
    return taken_ ? heads_[*taken_] : nullptr;
  }

  double FractionRead() const {
    double read = 0.0;
    for (const auto& file : files_) read += static_cast<double>(std::ftell(file->getFilePtr()));
    return total_size_ > 0 ? read / total_size_ : 0.0;
  }

 private:
  std::vector<std::unique_ptr<lcm::LogFile>> files_;
  std::vector<const lcm::LogEvent*> heads_;
  std::optional<size_t> taken_;
  double total_size_ = 0.0;
};

std::string Joined(const std::vector<fs::path>& paths) {
  std::string joined;
  for (const fs::path& path : paths) joined += (joined.empty() ? "" : ", ") + path.string();
  return joined;
}

}  // namespace

ReplaySummary RunReplay(const ReplayArgs& args, std::ostream& log, const ReplayObserver& observer) {
  const auto [carving, shape] = LoadReplayOptions(args);
  RigSetup setup = LoadRigSetup(carving.rig, carving.backgrounds);
  std::optional<ConfigurationSetup> configuration = LoadConfigurationSetup(shape);
  MergedLogs input(args.logs);
  ShapeWriter writer(args);
  log << "replay " << Joined(args.logs) << ": " << setup.rig.cameras.size()
      << " cameras, voxel size " << carving.carving.voxel_size << " mm\n";
  ReplayPipeline pipeline(carving, shape, std::move(configuration), std::move(setup), writer,
                          observer, args.progress);

  const std::regex image_channel(channels::kImagePattern);
  ReplaySummary summary;
  ProgressBar bar("replay", args.progress);
  while (const lcm::LogEvent* event = input.Next()) {
    ++summary.events;
    if (std::regex_match(event->channel, image_channel)) pipeline.OnEvent(*event, &summary);
    bar.Update(input.FractionRead(), std::to_string(summary.measured) + " shapes");
  }
  bar.Finish();
  pipeline.Finish(&summary);
  if (summary.measured > 0) {
    const double n = static_cast<double>(summary.measured);
    summary.mean_silhouette_ms /= n;
    summary.mean_carving_ms /= n;
    summary.mean_shape_ms /= n;
  }
  return summary;
}

void AddReplayCommand(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* command = app.add_subcommand(
      "replay", "Measure the shapes in recorded LCM logs of camera images, as fast as possible");
  command
      ->add_option("logs", args->logs,
                   "LCM logs (lcm-logger) with image_t on the camera channels: one per camera's "
                   "port, or one with all")
      ->required();
  command->add_option("--out", args->out, "shapes as JSON lines, as `shapesense offline` writes");
  command->add_option("--out-log", args->out_log, "shapes as a new LCM log of shape_t");
  command->add_option("--config", args->config,
                      "carving service config (config/carving_service.yaml)");
  command->add_option("--shape-config", args->shape_config,
                      "shape service config (config/shape_service.yaml)");
  command->add_option("--rig", args->rig, "rig file (overrides the configs)");
  command->add_option("--backgrounds", args->backgrounds,
                      "folder of <camera>.png (overrides the configs)");
  command->callback([args] {
    const ReplaySummary s = RunReplay(*args, std::cerr);
    std::cerr << std::fixed << std::setprecision(3) << "replay: " << s.images << " images, "
              << s.frame_sets << " frame-sets (" << s.dropped_sets << " incomplete dropped, "
              << s.rejected << " images rejected, " << s.not_carved << " not carved); measured "
              << s.measured << "; mean ms: silhouette " << s.mean_silhouette_ms << ", carving "
              << s.mean_carving_ms << ", shape " << s.mean_shape_ms << '\n';
  });
}

}  // namespace shapesense
