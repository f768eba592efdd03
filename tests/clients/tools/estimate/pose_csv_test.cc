#include "clients/tools/estimate/pose_csv.h"

#include <gtest/gtest.h>

#include <random>

#include "libs/core/error.h"
#include "libs/mechanics/synthetic_poses.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

TEST(PoseCsvTest, FormattedPosesParseBackExactly) {
  std::mt19937_64 rng(1);
  const TendonModel model(testing::CatheterOptions());
  SyntheticPoseOptions options;
  options.curvature_noise = 1e-4;
  options.tension_noise = 0.01;
  const std::vector<PoseSample> poses = SimulatePoses(model, options, rng);
  const std::vector<PoseSample> back = ParsePoseCsv(FormatPoseCsv(poses), "p.csv", 4, true);
  ASSERT_EQ(back.size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(back[i].displacements, poses[i].displacements);
    EXPECT_EQ(back[i].configuration, poses[i].configuration);
    EXPECT_EQ(back[i].tensions, poses[i].tensions);
  }
}

TEST(PoseCsvTest, ColumnsInAnyOrderOthersIgnoredCommentsAndBlankLinesSkipped) {
  const std::string text =
      "# poses of 2024-06-11\n"
      "time, kappa_z, y2, eps1, y0, kappa_x, y1, eps0\r\n"
      "\n"
      "0.5, -0.002, 3, 0.004, 1, 0.001, 2, 0.003\r\n"
      "  # a comment between poses\n"
      "1.0, 0, 6, 0, 4, 0, 5, 0\n";
  const std::vector<PoseSample> poses = ParsePoseCsv(text, "p.csv", 3, false);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0].displacements, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(poses[0].configuration, Eigen::Vector4d(0.001, -0.002, 0.003, 0.004));
  EXPECT_EQ(poses[1].displacements, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(poses[0].tensions.size(), 0);
}

void ExpectError(const std::string& text, int tendons, bool tensions, const std::string& fragment) {
  try {
    ParsePoseCsv(text, "data/poses.csv", tendons, tensions);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(PoseCsvTest, BadInputNamesFileLineAndColumn) {
  const std::string header = "y0,y1,y2,kappa_x,kappa_z,eps0,eps1\n";
  ExpectError(header + "1,2,3,0.1,0.2,0.3,0.4\n1,2,x3,0,0,0,0\n", 3, false,
              "data/poses.csv: line 3: y2: expected a number, got 'x3'");
  ExpectError(header + "1,2,3,0.1,0.2,0.3\n", 3, false,
              "data/poses.csv: line 2: expected 7 fields, got 6");
  ExpectError(header + "1,2,3,0.1,0.2,0.3,\n", 3, false, "line 2: eps1: expected a number, got ''");
  ExpectError(header + "1,2,3,0.1,inf,0.3,0.4\n", 3, false,
              "kappa_z: expected a number, got 'inf'");
  ExpectError(header + "1,2,3,0.1,0.2,0.3,0.4\n", 4, false,
              "data/poses.csv: line 1 (header): missing column 'y3'");
  ExpectError(header + "1,2,3,0.1,0.2,0.3,0.4\n", 3, true, "missing column 'tau0'");
  ExpectError("y0,y1,y2,y3,kappa_x,kappa_z,eps0,eps1\n", 3, false,
              "column 'y3', but the model has 3 tendons");
  ExpectError("y0,y1,y1,kappa_x,kappa_z,eps0,eps1\n", 3, false, "column 'y1' repeats");
  ExpectError("# nothing\n\n", 3, false, "data/poses.csv: empty");
}

}  // namespace
}  // namespace shapesense
