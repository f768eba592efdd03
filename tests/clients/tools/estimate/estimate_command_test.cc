#include "clients/tools/estimate/estimate_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "clients/tools/estimate/pose_csv.h"
#include "libs/mechanics/synthetic_poses.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

class EstimateCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(::testing::TempDir()) / ("shapesense_estimate_" + std::string(info->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // The model file starts 30% off the truth; the data come from the truth.
    ManipulatorOptions start = testing::CatheterOptions();
    start.stiffness = {520.0, 280.0, 3250.0, 560.0};
    Write("manipulator.yaml", FormatManipulatorYaml(start));
    std::mt19937_64 rng(8);
    SyntheticPoseOptions poses;
    poses.curvature_noise = 1e-5;
    poses.strain_noise = 5e-6;
    poses.tension_noise = 0.005;
    Write("poses.csv", FormatPoseCsv(SimulatePoses(truth_, poses, rng)));
    args_.model_path = Path("manipulator.yaml");
    args_.data_path = Path("poses.csv");
    args_.out_path = Path("result.json");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
  }
  nlohmann::json ReadJson(const std::string& name) const {
    std::ifstream file(dir_ / name);
    return nlohmann::json::parse(file);
  }
  int Run(std::string* log_text = nullptr) {
    std::ostringstream log;
    const int code = RunEstimate(args_, log);
    if (log_text) *log_text = log.str();
    return code;
  }
  void ExpectStiffnessRecovered(const nlohmann::json& stiffness) const {
    for (int j = 0; j < 4; ++j) {
      const double estimate = stiffness.at(kStiffnessNames[static_cast<size_t>(j)]).get<double>();
      EXPECT_NEAR(estimate / truth_.stiffness()(j), 1.0, 0.02)
          << kStiffnessNames[static_cast<size_t>(j)];
    }
  }

  const TendonModel truth_{testing::CatheterOptions()};
  fs::path dir_;
  EstimateArgs args_;
};

TEST_F(EstimateCommandTest, WritesTheStiffnessesTipErrorsAndPlot) {
  std::string log;
  ASSERT_EQ(Run(&log), 0) << log;
  const nlohmann::json result = ReadJson("result.json");
  EXPECT_EQ(result.at("method"), "output_error");
  EXPECT_EQ(result.at("poses"), 26);
  ExpectStiffnessRecovered(result.at("stiffness"));
  // Model from the estimate against the sensed tips: at the noise level.
  EXPECT_LT(result.at("tip_error_percent").get<double>(), 0.2);
  EXPECT_EQ(result.at("tip_error_percent_detail").at("per_pose").size(), 26u);
  EXPECT_GT(result.at("nominal").at("tip_error_percent").at("mean").get<double>(), 1.0);
  EXPECT_EQ(result.at("estimates").size(), 2u);
  EXPECT_TRUE(result.at("warnings").empty());
  const cv::Mat plot = cv::imread(Path("result.png"));
  ASSERT_FALSE(plot.empty());
  EXPECT_EQ(plot.cols, 2 * plot.rows);
  // Both colours are drawn: sensed (blue) and model (orange).
  cv::Mat blue, orange;
  cv::inRange(plot, cv::Scalar(150, 60, 0), cv::Scalar(230, 120, 60), blue);
  cv::inRange(plot, cv::Scalar(0, 100, 220), cv::Scalar(60, 160, 255), orange);
  EXPECT_GT(cv::countNonZero(blue), 100);
  EXPECT_GT(cv::countNonZero(orange), 100);
  EXPECT_NE(log.find("bend_x"), std::string::npos);
  EXPECT_NE(log.find("tip error"), std::string::npos);
}

TEST_F(EstimateCommandTest, WithTensionsTheTensionBasedEstimateIsWritten) {
  args_.use_tensions = true;
  args_.plot_path = Path("shapes.png");
  ASSERT_EQ(Run(), 0);
  const nlohmann::json result = ReadJson("result.json");
  EXPECT_EQ(result.at("method"), "tensions");
  EXPECT_EQ(result.at("estimates").size(), 3u);
  ExpectStiffnessRecovered(result.at("stiffness"));
  EXPECT_TRUE(fs::exists(dir_ / "shapes.png"));
  EXPECT_FALSE(fs::exists(dir_ / "result.png"));
}

TEST_F(EstimateCommandTest, WarnsByNameWhenAStiffnessIsPoorlyIdentified) {
  // Poses that bend only toward +-z leave bend_z unidentified.
  std::mt19937_64 rng(3);
  SyntheticPoseOptions poses;
  poses.bend_directions = {1.5707963267948966, -1.5707963267948966};
  poses.curvature_noise = 1e-5;
  Write("poses.csv", FormatPoseCsv(SimulatePoses(truth_, poses, rng)));
  std::string log;
  ASSERT_EQ(Run(&log), 0) << log;
  EXPECT_NE(log.find("warning: output_error: bend_z is not identified"), std::string::npos) << log;
  const nlohmann::json result = ReadJson("result.json");
  ASSERT_EQ(result.at("warnings").size(), 1u);
  EXPECT_TRUE(result.at("stiffness_std").at("bend_z").is_null() ||
              result.at("stiffness_std").at("bend_z").get<double>() > 0.1 * 400.0);
}

// Bad input: exit code 1, a message naming the file and place, nothing written.
class EstimateCommandBadInputTest : public EstimateCommandTest {
 protected:
  void ExpectRefused(const std::string& fragment) {
    std::string log;
    EXPECT_EQ(Run(&log), 1);
    EXPECT_NE(log.find(fragment), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(dir_ / "result.json"));
    EXPECT_FALSE(fs::exists(dir_ / "result.png"));
  }
};

TEST_F(EstimateCommandBadInputTest, MissingFiles) {
  args_.data_path = Path("nope.csv");
  ExpectRefused("nope.csv: cannot open for reading");
}

TEST_F(EstimateCommandBadInputTest, BadNumberInTheCsv) {
  Write("poses.csv",
        "y0,y1,y2,y3,kappa_x,kappa_z,eps0,eps1\n1,2,3,4,0,0,0,0\n1,2,3,4,0,zero,0,0\n");
  ExpectRefused("poses.csv: line 3: kappa_z: expected a number, got 'zero'");
}

TEST_F(EstimateCommandBadInputTest, TensionsAskedForButNotInTheCsv) {
  args_.use_tensions = true;
  Write("poses.csv", "y0,y1,y2,y3,kappa_x,kappa_z,eps0,eps1\n1,2,3,4,0,0,0,0\n");
  ExpectRefused("poses.csv: line 1 (header): missing column 'tau0'");
}

TEST_F(EstimateCommandBadInputTest, TooFewPoses) {
  Write("poses.csv", "y0,y1,y2,y3,kappa_x,kappa_z,eps0,eps1\n1,2,3,4,0,0,0,0\n");
  ExpectRefused("poses.csv: expected at least 3 poses, got 1");
}

TEST_F(EstimateCommandBadInputTest, BadModelKey) {
  Write("manipulator.yaml", "proximal_length: 600\ndistal_lenght: 160\n");
  ExpectRefused("manipulator.yaml: distal_lenght: unknown key");
}

TEST_F(EstimateCommandBadInputTest, ModelThatCannotBendAboutBothAxes) {
  Write("manipulator.yaml",
        "tendons:\n"
        "  - {dx: 1, dz: 0, length: 900, stiffness: 6000}\n"
        "  - {dx: 1, dz: 1, length: 900, stiffness: 6000}\n"
        "  - {dx: 1, dz: -1, length: 900, stiffness: 6000}\n");
  ExpectRefused("manipulator.yaml: tendons: expected a layout that can bend about both axes");
}

TEST_F(EstimateCommandBadInputTest, OutputDirectoryMissing) {
  args_.out_path = Path("no/such/dir/result.json");
  ExpectRefused("cannot write: no directory");
}

TEST_F(EstimateCommandTest, SubcommandParsesItsOptions) {
  CLI::App app("shapesense");
  AddEstimateCommand(app);
  const std::string out = Path("cli.json");
  ::testing::internal::CaptureStdout();
  try {
    app.parse("estimate --model " + args_.model_path + " --data " + args_.data_path + " --out " +
              out);
  } catch (const CLI::Error& e) {
    ADD_FAILURE() << e.what();
  }
  ::testing::internal::GetCapturedStdout();
  EXPECT_TRUE(fs::exists(out));
  EXPECT_TRUE(fs::exists(Path("cli.png")));
  CLI::App bad("shapesense");
  AddEstimateCommand(bad);
  ::testing::internal::CaptureStdout();
  try {
    bad.parse("estimate --model " + args_.model_path + " --data " + Path("nope.csv"));
    ADD_FAILURE() << "no error";
  } catch (const CLI::RuntimeError& e) {
    EXPECT_EQ(e.get_exit_code(), 1);
  }
  EXPECT_NE(::testing::internal::GetCapturedStdout().find("nope.csv"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
