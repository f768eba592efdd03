#include "libs/mechanics/manipulator_options.h"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>
#include <sstream>

#include "libs/core/error.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

constexpr const char* kValid = R"(
proximal_length: 500
distal_length: 150
tendons:
  - {dx: 1, dz: 0, length: 800, stiffness: 5000}
  - {dx: -0.5, dz: 0.866, length: 800, stiffness: 5000}
  - {dx: -0.5, dz: -0.866, length: 810, stiffness: 5200}
stiffness: {bend_x: 300, bend_z: 350, axial_proximal: 2000, axial_distal: 700}
)";

TEST(ManipulatorOptionsTest, ParsesEveryKey) {
  const ManipulatorOptions options = ParseManipulatorYaml(kValid, "m.yaml");
  EXPECT_EQ(options.proximal_length, 500.0);
  EXPECT_EQ(options.distal_length, 150.0);
  ASSERT_EQ(options.tendons.size(), 3u);
  EXPECT_EQ(options.tendons[2].dz, -0.866);
  EXPECT_EQ(options.tendons[2].length, 810.0);
  EXPECT_EQ(options.tendons[2].stiffness, 5200.0);
  EXPECT_EQ(options.stiffness.bend_z, 350.0);
  EXPECT_EQ(options.stiffness.axial_distal, 700.0);
}

TEST(ManipulatorOptionsTest, FormattedYamlParsesBackExactly) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const ManipulatorOptions options = testing::RandomOptions(rng);
    const ManipulatorOptions back = ParseManipulatorYaml(FormatManipulatorYaml(options), "f.yaml");
    ASSERT_EQ(back.tendons.size(), options.tendons.size());
    EXPECT_EQ(back.proximal_length, options.proximal_length);
    for (size_t i = 0; i < options.tendons.size(); ++i) {
      EXPECT_EQ(back.tendons[i].dx, options.tendons[i].dx);
      EXPECT_EQ(back.tendons[i].stiffness, options.tendons[i].stiffness);
    }
    EXPECT_EQ(back.stiffness.axial_proximal, options.stiffness.axial_proximal);
  }
}

TEST(ManipulatorOptionsTest, TheExampleConfigIsTheCatheterOfTheTests) {
  std::ifstream file(std::string(SHAPESENSE_SOURCE_DIR) + "/config/manipulator.yaml");
  ASSERT_TRUE(file) << "config/manipulator.yaml is missing";
  std::stringstream text;
  text << file.rdbuf();
  const ManipulatorOptions options = ParseManipulatorYaml(text.str(), "config/manipulator.yaml");
  const ManipulatorOptions catheter = testing::CatheterOptions();
  EXPECT_EQ(options.distal_length, 160.0);
  ASSERT_EQ(options.tendons.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(options.tendons[i].dx, catheter.tendons[i].dx, 1e-12);
    EXPECT_NEAR(options.tendons[i].dz, catheter.tendons[i].dz, 1e-12);
  }
}

void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    ParseManipulatorYaml(text, "cfg/m.yaml");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

TEST(ManipulatorOptionsTest, BadValuesNameFileKeyAndExpectation) {
  ExpectError(Replace(kValid, "stiffness: 5200", "stiffness: -1"),
              "cfg/m.yaml: tendons[2].stiffness: expected a positive number, got -1");
  ExpectError(Replace(kValid, "length: 800, stiffness: 5000}\n  - {dx: -0.5, dz: 0.866",
                      "lenght: 800, stiffness: 5000}\n  - {dx: -0.5, dz: 0.866"),
              "cfg/m.yaml: tendons[0].lenght: unknown key");
  ExpectError(Replace(kValid, "dz: -0.866, length", "dz: abc, length"),
              "cfg/m.yaml: tendons[2].dz: expected a number");
  ExpectError(Replace(kValid, "bend_z: 350", "bend_z: 0"),
              "cfg/m.yaml: stiffness.bend_z: expected a positive number, got 0");
  ExpectError(Replace(kValid, "distal_length: 150", "distal_length: -3"),
              "cfg/m.yaml: distal_length: expected a positive number");
  ExpectError("proximal_length: 500\n", "cfg/m.yaml: tendons: expected at least 3 tendons, got 0");
  ExpectError("tendons: 3\n", "cfg/m.yaml: tendons: expected a sequence");
  ExpectError("tendons: [\n", "cfg/m.yaml: not valid YAML");
}

TEST(ManipulatorOptionsTest, LayoutsThatCannotBendAboutBothAxesAreRejected) {
  // All three tendons on one side of the axis: no bending toward -x.
  ExpectError(R"(tendons:
  - {dx: 1, dz: 1, length: 800, stiffness: 5000}
  - {dx: 1, dz: -1, length: 800, stiffness: 5000}
  - {dx: 2, dz: 0, length: 800, stiffness: 5000}
)",
              "cfg/m.yaml: tendons: expected a layout that can bend about both axes");
  // Collinear through the axis: no bending about x at all.
  ExpectError(R"(tendons:
  - {dx: 1, dz: 0, length: 800, stiffness: 5000}
  - {dx: -1, dz: 0, length: 800, stiffness: 5000}
  - {dx: 0, dz: 0, length: 800, stiffness: 5000}
)",
              "bend about both axes");
}

TEST(ManipulatorOptionsTest, LayoutGapIsTheLargestEmptyAngle) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  for (int trial = 0; trial < 200; ++trial) {
    // Tendons within an arc of `spread` radians leave a gap of 2 pi - spread.
    const double spread = angle(rng), start = angle(rng);
    std::vector<TendonOptions> tendons;
    for (const double f : {0.0, 0.3, 1.0, 0.7}) {
      const double a = start + f * spread;
      tendons.push_back({std::cos(a), std::sin(a), 1.0, 1.0});
    }
    EXPECT_NEAR(TendonLayoutGap(tendons), std::max(2.0 * std::numbers::pi - spread, 0.4 * spread),
                1e-9);
  }
}

}  // namespace
}  // namespace shapesense
