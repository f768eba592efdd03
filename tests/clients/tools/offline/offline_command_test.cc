// `shapesense offline` end to end on small rendered datasets: the output's
// contract (docs/dataset.md), accuracy against the truth, and malformed input.
#include "clients/tools/offline_command.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libs/core/error.h"
#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "runtime/config_file.h"
#include "runtime/dataset.h"
#include "runtime/file_io.h"
#include "runtime/provenance.h"

namespace shapesense {
namespace {
namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    path =
        fs::temp_directory_path() /
        ("shapesense_offline_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Renders `frames` random scenes into a dataset; returns their truths.
std::vector<GroundTruth> WriteDataset(const fs::path& root, int frames) {
  SyntheticRigOptions rig_options;
  rig_options.seed = 3;
  const Rig rig = MakeSyntheticRig(rig_options);
  std::vector<GroundTruth> truths;
  for (int i = 0; i < frames; ++i) {
    const TubeScene scene = RandomScene(rig, 100 + static_cast<uint32_t>(i), 2.0, 2);
    const std::vector<RenderedView> views =
        RenderScene(rig, scene, RenderOptions{}, static_cast<uint32_t>(i));
    std::vector<cv::Mat> images, backgrounds;
    for (const RenderedView& view : views) {
      images.push_back(view.image);
      backgrounds.push_back(view.background);
    }
    if (i == 0) WriteDatasetHeader(root, rig, backgrounds);
    WriteFrame(root, rig, FrameName(i), images);
    truths.push_back(TruthOf(scene));
  }
  return truths;
}

std::vector<nlohmann::json> ReadLines(const fs::path& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  return lines;
}

Polyline ToPolyline(const nlohmann::json& points) {
  Polyline out;
  for (const auto& p : points)
    out.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  return out;
}

OfflineArgs ArgsFor(const fs::path& dir) {
  OfflineArgs args;
  args.dataset = dir / "data";
  args.out = dir / "out" / "shapes.jsonl";
  args.voxel_size = 2.0;  // a small table keeps the test quick
  args.progress = false;
  return args;
}

TEST(OfflineCommandTest, WritesOneAccurateLinePerFrameInOrder) {
  TempDir dir;
  const std::vector<GroundTruth> truths = WriteDataset(dir.path / "data", 3);
  std::ostringstream log;
  const OfflineSummary summary = RunOffline(ArgsFor(dir.path), log);
  EXPECT_EQ(summary.frames, 3);
  EXPECT_EQ(summary.measured, 3);
  const std::vector<nlohmann::json> lines = ReadLines(dir.path / "out" / "shapes.jsonl");
  ASSERT_EQ(lines.size(), 3u);
  for (size_t i = 0; i < lines.size(); ++i) {
    const nlohmann::json& line = lines[i];
    EXPECT_EQ(line["frame"], FrameName(static_cast<int>(i)));
    ASSERT_TRUE(line["valid"].get<bool>()) << line.dump();
    const Polyline centerline = ToPolyline(line["centerline"]);
    ASSERT_GE(centerline.size(), 2u);
    for (size_t k = 1; k < centerline.size(); ++k) {
      EXPECT_LE((centerline[k] - centerline[k - 1]).norm(), 2.0 + 1e-6);
    }
    EXPECT_EQ(line["curvature"].size(), centerline.size());
    // Base first, tip last, and close to the truth even with 2 mm voxels.
    EXPECT_LT((centerline.front() - truths[i].centerline.front()).norm(), 3.0);
    EXPECT_LT(RmsDistanceToPolyline(centerline, truths[i].centerline), 1.0);
    EXPECT_NEAR(line["arc_length"].get<double>(), truths[i].length, 3.0);
    EXPECT_EQ(line["markers"].size(), truths[i].markers.size());
    for (const char* stage : {"load", "silhouette", "carving", "shape", "total"}) {
      EXPECT_GE(line["stage_ms"][stage].get<double>(), 0.0) << stage;
    }
  }
}

TEST(OfflineCommandTest, TheEffectiveOptionsAndTheVersionAreWrittenBesideTheOutput) {
  TempDir dir;
  WriteDataset(dir.path / "data", 1);
  std::ostringstream log;
  RunOffline(ArgsFor(dir.path), log);
  const fs::path written = dir.path / "out" / "shapes.config.yaml";
  ASSERT_TRUE(fs::exists(written));
  const std::string text = ReadTextFile(written);
  EXPECT_EQ(text.rfind("# shapesense offline on ", 0), 0u) << text;
  EXPECT_NE(text.find(ProjectVersion()), std::string::npos) << text;
  EXPECT_FALSE(ProjectVersion().empty());
  // A config file as --config takes it, with the --voxel-size that was given.
  const PipelineOptions options = LoadOptionsFile<PipelineOptions>(written);
  EXPECT_EQ(options.carving.voxel_size, 2.0);
  EXPECT_EQ(options.silhouette.Validate(), "");
}

TEST(OfflineCommandTest, AFrameThatCannotBeReadIsReportedAndTheOthersStillMeasured) {
  TempDir dir;
  WriteDataset(dir.path / "data", 3);
  fs::remove(dir.path / "data" / "frames" / FrameName(1) / "cam1.png");
  std::ofstream(dir.path / "data" / "frames" / FrameName(2) / "cam0.png") << "not a png";
  std::ostringstream log;
  const OfflineSummary summary = RunOffline(ArgsFor(dir.path), log);
  EXPECT_EQ(summary.measured, 1);
  const std::vector<nlohmann::json> lines = ReadLines(dir.path / "out" / "shapes.jsonl");
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_TRUE(lines[0]["valid"].get<bool>());
  EXPECT_FALSE(lines[1]["valid"].get<bool>());
  EXPECT_NE(lines[1]["error"].get<std::string>().find("cam1.png: missing"), std::string::npos);
  EXPECT_NE(lines[2]["error"].get<std::string>().find("not a readable image"), std::string::npos);
}

TEST(OfflineCommandTest, AnEmptySceneIsReportedAsNotMeasured) {
  TempDir dir;
  WriteDataset(dir.path / "data", 1);
  // A frame that is just the background: nothing to measure.
  fs::create_directories(dir.path / "data" / "frames" / FrameName(1));
  for (const auto& entry : fs::directory_iterator(dir.path / "data" / "background")) {
    fs::copy_file(entry.path(),
                  dir.path / "data" / "frames" / FrameName(1) / entry.path().filename());
  }
  std::ostringstream log;
  RunOffline(ArgsFor(dir.path), log);
  const std::vector<nlohmann::json> lines = ReadLines(dir.path / "out" / "shapes.jsonl");
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_TRUE(lines[0]["valid"].get<bool>());
  EXPECT_FALSE(lines[1]["valid"].get<bool>());
  EXPECT_FALSE(lines[1]["error"].get<std::string>().empty());
}

void ExpectMalformed(const fs::path& dir, const std::string& fragment) {
  std::ostringstream log;
  try {
    RunOffline(ArgsFor(dir), log);
    ADD_FAILURE() << "accepted a malformed dataset; expected: " << fragment;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "shapes.jsonl")) << "wrote output for a malformed dataset";
}

TEST(OfflineCommandTest, MalformedDatasetsNameWhatIsWrongAndWriteNothing) {
  TempDir dir;
  const fs::path data = dir.path / "data";
  ExpectMalformed(dir.path, "not a dataset folder");
  WriteDataset(data, 1);
  const std::string rig = ReadTextFile(data / "rig.yaml");

  WriteFileAtomically(data / "rig.yaml", rig.substr(0, rig.find("workspace_min")));
  ExpectMalformed(dir.path, "rig.yaml: workspace_min: missing");
  WriteFileAtomically(data / "rig.yaml", "%YAML:1.0\n---\ncameras: 5\n");
  ExpectMalformed(dir.path, "rig.yaml: cameras: expected a non-empty sequence");
  WriteFileAtomically(data / "rig.yaml", rig);

  fs::rename(data / "background" / "cam2.png", data / "cam2.png");
  ExpectMalformed(dir.path, "background/cam2.png: missing");
  fs::rename(data / "cam2.png", data / "background" / "cam2.png");

  WritePng(data / "background" / "cam0.png", cv::Mat(10, 10, CV_8UC3, cv::Scalar::all(0)));
  ExpectMalformed(dir.path, "background/cam0.png: expected 640x480");
}

TEST(OfflineCommandTest, BadVoxelSizeAndConfigAreRejected) {
  TempDir dir;
  WriteDataset(dir.path / "data", 1);
  OfflineArgs args = ArgsFor(dir.path);
  args.voxel_size = -1.0;
  std::ostringstream log;
  EXPECT_THROW(RunOffline(args, log), InputError);
  args = ArgsFor(dir.path);
  args.config = dir.path / "pipeline.yaml";
  WriteFileAtomically(args.config, "carving:\n  voxel_sise: 1\n");
  try {
    RunOffline(args, log);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pipeline.yaml: carving.voxel_sise: unknown key"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace shapesense
