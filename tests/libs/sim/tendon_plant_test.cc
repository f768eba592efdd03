#include "libs/sim/tendon_plant.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "libs/geometry/polyline.h"
#include "libs/mechanics/configuration_geometry.h"
#include "tests/libs/mechanics/test_models.h"

namespace shapesense {
namespace {

Eigen::VectorXd Resting(const TendonModel& model) {
  return model.InverseWithMinimumTension(Configuration::Zero(), 0.5).displacements;
}

TEST(PlayOperatorTest, FollowsOnlyOnceThePlayIsTakenUp) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> step(-0.3, 0.3), width(0.0, 0.4);
  for (int trial = 0; trial < 100; ++trial) {
    const double w = width(rng);
    double input = 0.0, output = 0.0;
    for (int k = 0; k < 200; ++k) {
      const double next_input = input + step(rng);
      const double next_output = PlayOperator(output, next_input, w);
      // Never farther than half the play from the input...
      EXPECT_LE(std::abs(next_output - next_input), w / 2.0 + 1e-15);
      // ...and it moves only when the input pushes it, in the input's direction.
      if (std::abs(next_input - output) <= w / 2.0) {
        EXPECT_EQ(next_output, output);
      }
      if (next_output != output) {
        EXPECT_GT((next_output - output) * (next_input - input), 0.0);
        EXPECT_NEAR(std::abs(next_output - next_input), w / 2.0, 1e-12);
      }
      input = next_input;
      output = next_output;
    }
  }
}

TEST(PlayOperatorTest, AReversalMovesNothingUntilThePlayIsCrossed) {
  const double w = 0.2;
  double out = 0.0;
  for (int k = 0; k <= 20; ++k) out = PlayOperator(out, k / 20.0, w);
  EXPECT_NEAR(out, 1.0 - w / 2.0, 1e-12);  // lags the command going up
  const double top = out;
  out = PlayOperator(out, 1.0 - 0.15, w);  // back by less than the play
  EXPECT_EQ(out, top);
  out = PlayOperator(out, 0.5, w);         // going down it leads
  EXPECT_NEAR(out, 0.5 + w / 2.0, 1e-12);  // hysteresis: w between the two passes
}

TEST(TendonPlantTest, WithoutFrictionOrErrorsItIsTheModel) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 3.0);
  for (int trial = 0; trial < 100; ++trial) {
    const ManipulatorOptions options = testing::RandomOptions(rng);
    const TendonModel model(options);
    TendonPlant plant(options, TendonPlantOptions{}, Resting(model));
    Eigen::VectorXd y(model.num_tendons());
    for (int i = 0; i < y.size(); ++i) y(i) = u(rng);
    plant.Command(y);
    EXPECT_EQ(plant.tendon_displacements(), y);
    const TendonState expected = model.SolveWithSlack(y);
    EXPECT_LT((plant.configuration() - expected.configuration).norm(), 1e-15);
    EXPECT_EQ(plant.state().slack_tendons, expected.slack_tendons);
    EXPECT_EQ(plant.true_model().stiffness(), model.stiffness());
  }
}

TEST(TendonPlantTest, StiffnessesAreOffByTheFactorsAndTheSeededErrors) {
  const ManipulatorOptions nominal = testing::CatheterOptions();
  const TendonModel model(nominal);
  TendonPlantOptions options;
  options.stiffness_factor = {1.2, 0.8, 1.1, 0.9, 0.85};
  const TendonPlant fixed(nominal, options, Resting(model));
  EXPECT_NEAR(fixed.true_model().stiffness()(0), 1.2 * 400.0, 1e-9);
  EXPECT_NEAR(fixed.true_model().stiffness()(3), 0.9 * 800.0, 1e-9);
  EXPECT_NEAR(fixed.true_model().options().tendons[2].stiffness, 0.85 * 6000.0, 1e-9);

  options = TendonPlantOptions{};
  options.random_stiffness_error = 0.2;
  options.tendon_play = 0.1;
  options.tendon_play_spread = 0.5;
  for (uint32_t seed = 0; seed < 50; ++seed) {
    options.seed = seed;
    const TendonPlant a(nominal, options, Resting(model)), b(nominal, options, Resting(model));
    EXPECT_EQ(a.true_model().stiffness(), b.true_model().stiffness()) << "same seed, same plant";
    EXPECT_EQ(a.play_widths(), b.play_widths());
    const Eigen::Vector4d ratio = a.true_model().stiffness().cwiseQuotient(model.stiffness());
    EXPECT_LE((ratio.array() - 1.0).abs().maxCoeff(), 0.2 + 1e-12);
    EXPECT_LE((a.play_widths().array() - 0.1).abs().maxCoeff(), 0.05 + 1e-12);
    options.seed = seed + 1000;
    const TendonPlant c(nominal, options, Resting(model));
    EXPECT_NE(a.true_model().stiffness(), c.true_model().stiffness()) << "another seed";
  }
}

TEST(TendonPlantTest, PlayMakesTheShapeDependOnTheWayThere) {
  const ManipulatorOptions nominal = testing::CatheterOptions();
  const TendonModel model(nominal);
  TendonPlantOptions options;
  options.tendon_play = 0.2;
  const Eigen::VectorXd start = Resting(model);
  const Eigen::VectorXd bend = start + Eigen::Vector4d(1.0, 0.0, -0.3, 0.0);
  TendonPlant plant(nominal, options, start);
  EXPECT_EQ(plant.tendon_displacements(), start) << "starts centred in its play";
  // To `bend` from below, then overshoot and come back: same command, other shape.
  plant.Command(bend);
  const Configuration from_below = plant.configuration();
  plant.Command(bend + Eigen::Vector4d(0.5, 0.0, -0.5, 0.0));
  plant.Command(bend);
  const Configuration from_above = plant.configuration();
  EXPECT_GT((from_above - from_below).head<2>().norm() * 160.0, 0.05);
  // A small reversal moves no tendon at all.
  const Eigen::VectorXd before = plant.tendon_displacements();
  plant.Command(bend + Eigen::Vector4d(0.1, 0.0, -0.1, 0.0));
  EXPECT_EQ(plant.tendon_displacements(), before);
}

TEST(TendonPlantTest, PushedTendonsGoSlackInsteadOfPushing) {
  const ManipulatorOptions nominal = testing::CatheterOptions();
  TendonPlant plant(nominal, TendonPlantOptions{}, Resting(TendonModel(nominal)));
  plant.Command(Eigen::Vector4d(2.0, 0.5, -2.0, 0.5));
  const TendonState& state = plant.state();
  ASSERT_TRUE(state.has_slack());
  EXPECT_NE(std::find(state.slack_tendons.begin(), state.slack_tendons.end(), 2),
            state.slack_tendons.end());
  for (const int i : state.slack_tendons) {
    EXPECT_EQ(state.tensions(i), 0.0);
    EXPECT_GT(state.slack_lengths(i), 0.0);
  }
  EXPECT_GT(state.tensions(0), 0.0);
  EXPECT_GE(state.tensions.minCoeff(), 0.0);
}

TEST(TendonPlantTest, TheCentrelineRunsFromTheBaseToTheTip) {
  const ManipulatorOptions nominal = testing::CatheterOptions();
  const TendonModel model(nominal);
  TendonPlantOptions options;
  options.centerline_spacing = 0.5;
  TendonPlant plant(nominal, options, Resting(model));
  plant.Command(Resting(model) + Eigen::Vector4d(1.5, 0.4, 0.0, 0.0));
  const Polyline line = plant.Centerline();
  EXPECT_LT(line.front().norm(), 1e-12);
  EXPECT_LT((line.back() - plant.BaseFromTip().translation()).norm(), 1e-9);
  const SectionLengths compressed = CompressedLengths(plant.configuration(), model.lengths());
  EXPECT_NEAR(PolylineLength(line), compressed.proximal + compressed.distal, 1e-3);
  for (size_t i = 1; i < line.size(); ++i) EXPECT_LE((line[i] - line[i - 1]).norm(), 0.5 + 1e-9);
}

TEST(TendonPlantTest, OptionsLoadFromYamlAndRefuseBadValues) {
  const TendonPlantOptions loaded = OptionsFromYamlText<TendonPlantOptions>(
      "stiffness_factor: {bend_x: 1.2, tendon: 0.9}\ntendon_play: 0.1\nseed: 5\n", "plant.yaml");
  EXPECT_EQ(loaded.stiffness_factor.bend_x, 1.2);
  EXPECT_EQ(loaded.stiffness_factor.bend_z, 1.0);
  EXPECT_EQ(loaded.seed, 5u);
  EXPECT_THROW(OptionsFromYamlText<TendonPlantOptions>("stiffness_factor: {bend_x: 3}", "p"),
               InputError);
  EXPECT_THROW(OptionsFromYamlText<TendonPlantOptions>("tendon_play: -0.1", "p"), InputError);
  EXPECT_THROW(OptionsFromYamlText<TendonPlantOptions>("random_stiffness_error: 0.7", "p"),
               InputError);
  const ManipulatorOptions nominal = testing::CatheterOptions();
  EXPECT_THROW(TendonPlant(nominal, TendonPlantOptions{}, Eigen::Vector3d::Zero()),
               std::invalid_argument);
  TendonPlant plant(nominal, TendonPlantOptions{}, Eigen::Vector4d::Zero());
  EXPECT_THROW(plant.Command(Eigen::Vector4d(0.0, std::nan(""), 0.0, 0.0)), std::invalid_argument);
}

}  // namespace
}  // namespace shapesense
