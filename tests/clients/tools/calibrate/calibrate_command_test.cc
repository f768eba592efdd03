// `shapesense calibrate` end to end through its command line: OpenCV's sample
// pictures, a rendered three-camera rig from images to rig file, backgrounds,
// registration, and bad input (clear message, non-zero exit, nothing written).
#include "clients/tools/calibrate/calibrate_command.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "libs/calibration/synthetic_board.h"
#include "libs/camera/rig_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "tests/libs/calibration/calibration_scenes.h"

namespace shapesense {
namespace {
namespace fs = std::filesystem;
using testing::AngleBetweenDeg;

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() /
           ("shapesense_calibrate_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// Parses a command line through AddCalibrateCommand, as `shapesense` does.
void RunCommandLine(const std::vector<std::string>& words) {
  CLI::App app{"shapesense"};
  app.require_subcommand(1);
  AddCalibrateCommand(app);
  std::vector<std::string> reversed(words.rbegin(), words.rend());
  app.parse(reversed);
}

void WriteImage(const fs::path& path, const cv::Mat& image) {
  fs::create_directories(path.parent_path());
  ASSERT_TRUE(cv::imwrite(path.string(), image)) << path;
}

TEST(CalibrateCommandTest, IntrinsicsOfOpenCvSamplePicturesMatchOpenCv) {
  TempDir dir;
  std::vector<std::vector<cv::Point2f>> opencv_corners;
  for (const std::string& number : testing::OpenCvSampleNumbers()) {
    const fs::path picture = testing::OpenCvSampleDir() / ("left" + number + ".jpg");
    ASSERT_TRUE(fs::exists(picture))
        << picture << " is missing: install opencv-doc (deploy/install-deps.sh)";
    fs::create_directories(dir.path / "left");
    fs::copy_file(picture, dir.path / "left" / picture.filename());
    const cv::Mat grey = cv::imread(picture.string(), cv::IMREAD_GRAYSCALE);
    std::vector<cv::Point2f> corners;
    ASSERT_TRUE(cv::findChessboardCorners(grey, cv::Size(9, 6), corners, 11));
    cv::cornerSubPix(grey, corners, cv::Size(11, 11), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 30, 1e-4));
    opencv_corners.push_back(corners);
  }
  RunCommandLine({"calibrate", "intrinsics", "--images", (dir.path / "left").string(), "--pattern",
                  "chessboard", "--cols", "9", "--rows", "6", "--square", "25", "--out",
                  (dir.path / "out" / "left.yaml").string(), "--overlays",
                  (dir.path / "overlays").string()});
  const std::string yaml = ReadTextFile(dir.path / "out" / "left.yaml");
  const Camera camera = ParseCameraYaml(yaml, "left.yaml");
  EXPECT_EQ(camera.name, "left");
  cv::FileStorage storage(yaml, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  const double rms = storage["reprojection_error"].real();

  std::vector<cv::Point3f> board;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) board.emplace_back(25.0f * c, 25.0f * r, 0.0f);
  }
  cv::Mat k, d, rvecs, tvecs;
  const double opencv_rms =
      cv::calibrateCamera(std::vector<std::vector<cv::Point3f>>(opencv_corners.size(), board),
                          opencv_corners, cv::Size(640, 480), k, d, rvecs, tvecs);
  EXPECT_GT(rms, 0.05);
  EXPECT_LT(rms, 1.05 * opencv_rms) << "OpenCV's calibrateCamera on its sample pipeline's corners";
  EXPECT_NEAR(camera.camera_matrix(0, 0) / k.at<double>(0, 0), 1.0, 0.01);
  int overlays = 0;
  for (const auto& entry : fs::directory_iterator(dir.path / "overlays")) {
    overlays += entry.path().extension() == ".png";
  }
  EXPECT_EQ(overlays, 13);
}

// The rendered three-camera rig from pictures to rig file: each camera's
// intrinsics from its own views, then the extrinsics from shared views.
// Renders 12 views of the board for each camera's intrinsics into
// dir/intrinsics/<camera>/ and calibrates them into dir/<camera>.yaml.
void CalibrateEachCamera(const fs::path& dir, const std::vector<Camera>& truth,
                         const CalibrationBoard& board, std::mt19937& rng) {
  for (const Camera& camera : truth) {
    const BoardViewRenderer renderer(camera);
    for (int i = 0; i < 12; ++i) {
      BoardRenderOptions render;
      render.seed = static_cast<uint32_t>(rng());
      WriteImage(dir / "intrinsics" / camera.name / ("view" + std::to_string(i) + ".png"),
                 renderer.Render(board, testing::IntrinsicsBoardPose(camera, board, rng), render));
    }
    RunCommandLine({"calibrate", "intrinsics", "--images",
                    (dir / "intrinsics" / camera.name).string(), "--cols", "9", "--rows", "6",
                    "--square", "20", "--out", (dir / (camera.name + ".yaml")).string()});
  }
}

// Renders `views` synchronised views of the board lying near the origin into
// dir/views/<camera>/00<v>.png; returns world_from_board per view.
std::vector<Pose3> WriteRigViews(const fs::path& dir, const std::vector<Camera>& truth,
                                 const CalibrationBoard& board, int views, std::mt19937& rng) {
  std::vector<Pose3> world_from_board(static_cast<size_t>(views));
  for (Pose3& pose : world_from_board) pose = testing::RigBoardPose(board, rng);
  for (const Camera& camera : truth) {
    const BoardViewRenderer renderer(camera);
    for (int v = 0; v < views; ++v) {
      BoardRenderOptions render;
      render.seed = static_cast<uint32_t>(rng());
      WriteImage(
          dir / "views" / camera.name / ("00" + std::to_string(v) + ".png"),
          renderer.Render(board, camera.cam_from_world * world_from_board[static_cast<size_t>(v)],
                          render));
    }
  }
  return world_from_board;
}

TEST(CalibrateCommandTest, RenderedRigFromPicturesToRigFileWithinSpec) {
  TempDir dir;
  const std::vector<Camera> truth = testing::ThreeCameraRig(31);
  BoardOptions options;
  options.square = 20.0;
  const CalibrationBoard board(options);
  std::mt19937 rng(32);
  CalibrateEachCamera(dir.path, truth, board, rng);
  const std::vector<Pose3> world_from_board = WriteRigViews(dir.path, truth, board, 5, rng);
  std::vector<std::string> words = {
      "calibrate",       "extrinsics", "--views",         (dir.path / "views").string(),
      "--cols",          "9",          "--rows",          "6",
      "--square",        "20",         "--anchor-view",   "1",
      "--workspace-min", "-100,-90,0", "--workspace-max", "100,90,200",
      "--base-point",    "0,0,5",      "--out",           (dir.path / "rig.yaml").string()};
  for (const Camera& camera : truth) {
    words.push_back("--intrinsics");
    words.push_back(camera.name + "=" + (dir.path / (camera.name + ".yaml")).string());
  }
  RunCommandLine(words);

  const Rig rig = ParseRigYaml(ReadTextFile(dir.path / "rig.yaml"), "rig.yaml");
  ASSERT_EQ(rig.cameras.size(), 3u);
  EXPECT_TRUE(rig.workspace_min.isApprox(Vec3(-100, -90, 0)));
  EXPECT_TRUE(rig.workspace_max.isApprox(Vec3(100, 90, 200)));
  EXPECT_TRUE(rig.base_point.isApprox(Vec3(0, 0, 5)));
  Pose3 board_from_anchored = Pose3::Identity();
  board_from_anchored.linear() = Vec3(1.0, -1.0, -1.0).asDiagonal();
  const Pose3 truth_world_from_anchored = world_from_board[1] * board_from_anchored;
  for (size_t c = 0; c < 3; ++c) {
    SCOPED_TRACE(truth[c].name);
    const Camera& got = rig.cameras[c];
    EXPECT_EQ(got.name, truth[c].name);
    const double focal_error = got.camera_matrix(0, 0) / truth[c].camera_matrix(0, 0) - 1.0;
    EXPECT_LT(std::abs(focal_error), 0.005);
    EXPECT_NEAR(got.camera_matrix(1, 1) / truth[c].camera_matrix(1, 1), 1.0, 0.005);
    const Pose3 expected = truth[c].cam_from_world * truth_world_from_anchored;
    const double position = (got.Center() - expected.inverse().translation()).norm();
    const double rotation = AngleBetweenDeg(got.cam_from_world.linear(), expected.linear());
    EXPECT_LT(position, 0.5);
    EXPECT_LT(rotation, 0.1);
    std::printf("[ measured ] %s: focal %.3f%% off, position %.3f mm, rotation %.4f deg\n",
                got.name.c_str(), 100.0 * std::abs(focal_error), position, rotation);
  }
}

TEST(CalibrateCommandTest, BackgroundIsTheMedianOfEachCamerasFrames) {
  TempDir dir;
  cv::RNG rng(3);
  std::vector<cv::Mat> empty_scenes;
  for (const std::string camera : {"cam0", "cam1"}) {
    cv::Mat scene(48, 64, CV_8UC3);
    rng.fill(scene, cv::RNG::UNIFORM, 0, 256);
    empty_scenes.push_back(scene);
    for (int i = 0; i < 5; ++i) {
      cv::Mat frame = scene.clone();
      if (i % 2 == 0 && i > 0) frame(cv::Rect(5 * i, 3 * i, 20, 15)).setTo(cv::Scalar(255, 0, 255));
      WriteImage(dir.path / "frames" / camera / ("f" + std::to_string(i) + ".png"), frame);
    }
  }
  RunCommandLine({"calibrate", "background", "--frames", (dir.path / "frames").string(), "--out",
                  (dir.path / "background").string()});
  for (size_t c = 0; c < 2; ++c) {
    const cv::Mat median =
        ReadBgrImage(dir.path / "background" / ("cam" + std::to_string(c) + ".png"));
    EXPECT_EQ(cv::norm(median, empty_scenes[c], cv::NORM_INF), 0.0);
  }
}

TEST(CalibrateCommandTest, RegisterReportsTransformAndErrorPerAxis) {
  TempDir dir;
  Pose3 truth = Pose3::Identity();
  truth.linear() = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  truth.translation() = Vec3(10, -20, 30);
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.2);
  const auto point = [](int i) {
    const int row = i / 3;  // a 3 x 3 grid, alternately raised
    return Vec3(40.0 * (i % 3), 30.0 * row, 25.0 * (i % 2));
  };
  std::ostringstream reference, sensed;
  sensed << "# stylus tips found in the voxels\nname,x,y,z\n";
  for (int i = 0; i < 8; ++i) {
    sensed << "P" << i << ',' << point(i).x() << ',' << point(i).y() << ',' << point(i).z() << '\n';
  }
  reference << "name,x,y,z\n";
  for (int i = 7; i >= 0; --i) {  // another order: the points pair by name
    const Vec3 r = truth * point(i) + Vec3(noise(rng), noise(rng), noise(rng));
    reference << "P" << i << ',' << r.x() << ',' << r.y() << ',' << r.z() << '\n';
  }
  WriteFileAtomically(dir.path / "reference.csv", reference.str());
  WriteFileAtomically(dir.path / "sensed.csv", sensed.str());
  RunCommandLine({"calibrate", "register", "--reference", (dir.path / "reference.csv").string(),
                  "--sensed", (dir.path / "sensed.csv").string(), "--out",
                  (dir.path / "report").string()});
  cv::FileStorage yaml(ReadTextFile(dir.path / "report" / "registration.yaml"),
                       cv::FileStorage::READ | cv::FileStorage::MEMORY);
  cv::Mat translation;
  yaml["reference_from_sensed_translation"] >> translation;
  EXPECT_LT((Vec3(translation.at<double>(0), translation.at<double>(1), translation.at<double>(2)) -
             truth.translation())
                .norm(),
            1.0);
  EXPECT_LT(yaml["rms"].real(), 0.5);
  EXPECT_EQ(yaml["points"].size(), 8u);
  EXPECT_FALSE(ReadBgrImage(dir.path / "report" / "registration.png").empty());
  EXPECT_NE(ReadTextFile(dir.path / "report" / "report.md").find("| RMS |"), std::string::npos);
}

// Runs a command line expecting an InputError that contains `expected`.
void ExpectInputError(const std::vector<std::string>& words, const std::string& expected) {
  try {
    RunCommandLine(words);
    ADD_FAILURE() << "expected an InputError with: " << expected;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

cv::Mat ChessboardPicture(uint32_t seed) {
  const Camera camera = testing::ThreeCameraRig()[0];
  const CalibrationBoard board(BoardOptions{});
  std::mt19937 rng(seed);
  return RenderBoardView(camera, board, testing::IntrinsicsBoardPose(camera, board, rng));
}

TEST(CalibrateCommandTest, BadInputGivesAClearMessageAndWritesNothing) {
  TempDir dir;
  const fs::path out = dir.path / "cam.yaml";
  const auto intrinsics = [&](const fs::path& images, const std::string& cols) {
    return std::vector<std::string>{"calibrate", "intrinsics", "--images", images.string(),
                                    "--cols",    cols,         "--rows",   "6",
                                    "--square",  "25",         "--out",    out.string()};
  };
  for (int i = 0; i < 2; ++i) {
    WriteImage(dir.path / "no_board" / ("v" + std::to_string(i) + ".png"),
               cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 100, 110)));
    WriteImage(dir.path / "board" / ("v" + std::to_string(i) + ".png"), ChessboardPicture(i));
  }
  ExpectInputError(intrinsics(dir.path / "no_board", "9"), "no chessboard 9x6 inner corners");
  ExpectInputError(intrinsics(dir.path / "board", "8"), "check --pattern, and --cols/--rows");
  fs::create_directories(dir.path / "empty");
  ExpectInputError(intrinsics(dir.path / "empty", "9"), "no images");
  ExpectInputError(intrinsics(dir.path / "missing", "9"), "no such folder");
  WriteFileAtomically(dir.path / "board" / "v9.png", "not a picture");
  ExpectInputError(intrinsics(dir.path / "board", "9"), "v9.png: not a readable image");
  EXPECT_FALSE(fs::exists(out));
}

TEST(CalibrateCommandTest, ACameraThatNeverSeesTheBoardStopsExtrinsics) {
  TempDir dir;
  Camera camera = testing::ThreeCameraRig()[0];
  camera.cam_from_world = Pose3::Identity();
  for (const std::string name : {"cam0", "cam1"}) {
    camera.name = name;
    WriteFileAtomically(dir.path / (name + ".yaml"), FormatCalibratedCameraYaml(camera, 0.1));
    for (int i = 0; i < 2; ++i) {
      WriteImage(dir.path / "views" / name / ("v" + std::to_string(i) + ".png"),
                 name == "cam0" ? ChessboardPicture(10 + i)
                                : cv::Mat(480, 640, CV_8UC3, cv::Scalar(80, 80, 80)));
    }
  }
  const fs::path out = dir.path / "rig.yaml";
  std::vector<std::string> words = {"calibrate",    "extrinsics",
                                    "--views",      (dir.path / "views").string(),
                                    "--cols",       "9",
                                    "--rows",       "6",
                                    "--square",     "25",
                                    "--out",        out.string(),
                                    "--intrinsics", "cam0=" + (dir.path / "cam0.yaml").string()};
  ExpectInputError(words, "camera 'cam1' has no intrinsics");
  words.push_back("--intrinsics");
  words.push_back("cam1=" + (dir.path / "cam1.yaml").string());
  ExpectInputError(words, "camera 'cam1' never sees the board");
  EXPECT_FALSE(fs::exists(out));
}

// `shapesense calibrate` exits non-zero with the message on stderr.
TEST(CalibrateCommandTest, TheExecutableExitsNonZeroOnBadInput) {
  TempDir dir;
  WriteImage(dir.path / "no_board" / "v0.png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(90, 90, 90)));
  const fs::path out = dir.path / "cam.yaml";
  const std::string command = std::string(SHAPESENSE_BINARY) + " calibrate intrinsics --images " +
                              (dir.path / "no_board").string() +
                              " --cols 9 --rows 6 --square 25 --out " + out.string() + " 2> " +
                              (dir.path / "stderr.txt").string();
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_NE(ReadTextFile(dir.path / "stderr.txt").find("shapesense: error:"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace shapesense
