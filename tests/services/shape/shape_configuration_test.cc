// The shape service with the configuration section on: behind the carving
// service, every shape of a manipulator scene carries q (has_configuration,
// q, configuration_residual_mm) close to the truth; a shape whose tape band
// is hidden carries none and the status says why; the config section loads
// the model file relative to the config and names bad keys and files; the
// shipped config documents the section with its defaults.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "libs/mechanics/configuration_geometry.h"
#include "libs/sim/manipulator_scene.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/shape_message.h"
#include "services/carving/carving_service.h"
#include "services/shape/shape_service.h"
#include "tests/support/service_test_options.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using testing::HandleUntil;
using testing::TestRig;

constexpr SectionLengths kRest{60.0, 140.0};

// The base on the workspace's bottom face, its axis along world +z.
ShapeConfigurationOptions ConfigurationSection(const Rig& rig) {
  ShapeConfigurationOptions section;
  section.enabled = true;
  section.manipulator = "(in memory)";
  section.base.base_position = {rig.base_point.x(), rig.base_point.y(), rig.base_point.z()};
  section.base.base_rotation = {std::numbers::pi / 2.0, 0.0, 0.0};
  return section;
}

class ShapeConfigurationTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    rig_ = new TestRig(6);
    renderer_ = new SceneRenderer(rig_->rig());
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete rig_;
  }

  ShapeConfigurationTest() {
    options_.configuration = ConfigurationSection(rig_->rig());
    setup_.geometry = {kRest, options_.configuration.base.WorldFromBase(),
                       options_.configuration.tapes};
    bus_.Subscribe<shape_t>(channels::kShape, [this](const shape_t& s, const std::string&,
                                                     int64_t) { shapes_.push_back(s); });
  }

  TubeScene Scene(const Configuration& q) const {
    return SceneOfConfiguration(q, kRest, setup_.geometry.world_from_base, {});
  }

  // Renders the scene, publishes it as camera images and waits for its shape.
  const shape_t* Measure(const TubeScene& scene, int64_t seq, CarvingService& carving,
                         ShapeService& shape) {
    const size_t before = shapes_.size();
    std::vector<image_t> images;
    const std::vector<RenderedView> views =
        renderer_->Render(scene, RenderOptions{}, static_cast<uint32_t>(seq));
    for (size_t k = 0; k < views.size(); ++k) {
      images.push_back(
          testing::MakeImageMessage(views[k].image, rig_->rig().cameras[k].name, seq, 0));
    }
    testing::Stamp(&images, NowUtime());
    for (const image_t& image : images) bus_.Publish(channels::Image(image.camera), image);
    const bool done = HandleUntil(
        bus_, [&] { return shapes_.size() > before; },
        [&](int64_t now) {
          carving.Poll(now);
          shape.Poll(now);
        });
    return done ? &shapes_.back() : nullptr;
  }

  static TestRig* rig_;
  static SceneRenderer* renderer_;
  ShapeServiceOptions options_ = testing::TestShapeOptions();
  ConfigurationSetup setup_;
  LcmBus bus_{"memq://"};
  std::vector<shape_t> shapes_;
};
TestRig* ShapeConfigurationTest::rig_ = nullptr;
SceneRenderer* ShapeConfigurationTest::renderer_ = nullptr;

TEST_F(ShapeConfigurationTest, EveryShapeCarriesTheConfigurationCloseToTheTruth) {
  CarvingService carving(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  ShapeService shape(options_, rig_->rig(), bus_, setup_);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    // Bends of 30-110 degrees in any plane, strains 0-3%.
    const double kappa = (30.0 + 80.0 * unit(rng)) * std::numbers::pi / 180.0 / kRest.distal;
    const double phi = 2.0 * std::numbers::pi * unit(rng);
    const Configuration q(kappa * std::sin(phi), -kappa * std::cos(phi), 0.03 * unit(rng),
                          0.03 * unit(rng));
    const TubeScene scene = Scene(q);
    const shape_t* measured = Measure(scene, 40 + i, carving, shape);
    ASSERT_NE(measured, nullptr);
    ASSERT_TRUE(measured->valid) << measured->error;
    ASSERT_TRUE(measured->has_configuration) << shape.Status(NowUtime()).last_error;
    const std::optional<Configuration> sensed = MessageConfiguration(*measured);
    ASSERT_TRUE(sensed.has_value());
    const Vec3 tip = setup_.geometry.world_from_base * BaseFromTip(*sensed, kRest).translation();
    const double tip_error = (tip - TruthOf(scene).tip).norm();
    const double curvature_error = std::abs(sensed->head<2>().norm() - kappa) / kappa;
    std::printf(
        "q %d: curvature %.3f%%, eps0 %.1e, eps1 %.1e, tip from q %.3f mm, arc fit RMS %.3f mm\n",
        i, 100.0 * curvature_error, std::abs((*sensed)(2) - q(2)), std::abs((*sensed)(3) - q(3)),
        tip_error, measured->configuration_residual_mm);
    // 2 mm voxels here (the chain test at 1 mm holds the tighter targets).
    EXPECT_LT(tip_error, 0.5);
    EXPECT_LT(curvature_error, 0.01);
    EXPECT_GT(measured->configuration_residual_mm, 0.0);
    EXPECT_LT(measured->configuration_residual_mm, 0.2);
  }
  EXPECT_EQ(shape.Status(NowUtime()).errors, 0) << shape.Status(NowUtime()).last_error;
}

TEST_F(ShapeConfigurationTest, AHiddenBandLeavesNoConfigurationAndTheStatusSaysWhy) {
  CarvingService carving(testing::TestCarvingOptions(), rig_->Setup(), bus_);
  ShapeService shape(options_, rig_->rig(), bus_, setup_);
  TubeScene scene = Scene(Configuration(0.006, -0.004, 0.01, 0.02));
  scene.tapes.pop_back();
  const shape_t* measured = Measure(scene, 50, carving, shape);
  ASSERT_NE(measured, nullptr);
  EXPECT_TRUE(measured->valid) << measured->error;
  EXPECT_FALSE(measured->has_configuration);
  // The worker notes the reason just after publishing the shape.
  HandleUntil(bus_, [&] { return !shape.Status(NowUtime()).last_error.empty(); });
  const std::string note = shape.Status(NowUtime()).last_error;
  EXPECT_NE(note.find("no configuration: saw 1 tape markers, the layout has 2"), std::string::npos)
      << note;
}

// A tape colour that matches nothing leaves the shape without q, and the
// status says it is the colour, not a band out of view.
TEST_F(ShapeConfigurationTest, ATapeColourThatMatchesNothingIsNamedAndNoQIsMeasured) {
  CarvingServiceOptions carving_options = testing::TestCarvingOptions();
  carving_options.silhouette.tape.hue_deg = {200.0, 240.0};  // blue; the tapes are red
  CarvingService carving(carving_options, rig_->Setup(), bus_);
  ShapeService shape(options_, rig_->rig(), bus_, setup_);
  const shape_t* measured =
      Measure(Scene(Configuration(0.006, -0.004, 0.01, 0.02)), 60, carving, shape);
  ASSERT_NE(measured, nullptr);
  EXPECT_TRUE(measured->valid) << measured->error;
  EXPECT_EQ(measured->num_markers, 0);
  EXPECT_FALSE(measured->has_configuration);
  HandleUntil(bus_, [&] { return !shape.Status(NowUtime()).last_error.empty(); });
  const std::string note = shape.Status(NowUtime()).last_error;
  EXPECT_NE(note.find("no camera sees any tape"), std::string::npos) << note;
  EXPECT_NE(note.find("tape colour"), std::string::npos) << note;
}

TEST_F(ShapeConfigurationTest, TheShapeStageThatReplaySharesSensesQToo) {
  const CarvingServiceOptions carving_options = testing::TestCarvingOptions();
  const CarvingStage carving(rig_->rig(), rig_->backgrounds(), carving_options.silhouette,
                             carving_options.carving);
  const ShapeStage stage(rig_->rig(), options_.shape, setup_);
  EXPECT_TRUE(stage.senses_configuration());
  const Configuration q(-0.004, 0.007, 0.02, 0.01);
  FrameSetAssembler assembler(CameraNames(rig_->rig()), carving_options.assembly);
  std::optional<FrameSet> set;
  const std::vector<RenderedView> views = renderer_->Render(Scene(q), RenderOptions{}, 9);
  for (size_t k = 0; k < views.size(); ++k) {
    AssemblyResult result = assembler.Add(
        testing::MakeImageMessage(views[k].image, rig_->rig().cameras[k].name, 9, 0), NowUtime());
    if (result.completed) set = std::move(result.completed);
  }
  ASSERT_TRUE(set.has_value());
  CarvingOutput carved;
  ASSERT_EQ(carving.Process(*set, &carved), "");
  ShapeOutput out;
  ASSERT_EQ(stage.Process(carved.message, &carved.compact, &out), "");
  ASSERT_TRUE(out.configuration.valid) << out.configuration.reason;
  EXPECT_TRUE(out.message.has_configuration);
  EXPECT_EQ(MessageConfiguration(out.message), out.configuration.q);
  EXPECT_EQ(out.message.configuration_residual_mm, out.configuration.rms_residual);
  EXPECT_LT((out.configuration.q.head<2>() - q.head<2>()).norm(), 0.01 * q.head<2>().norm());
  // A geometry that fails validation is refused when the stage is made.
  ConfigurationSetup bad = setup_;
  bad.geometry.rest.distal = 5.0;
  EXPECT_THROW(ShapeStage(rig_->rig(), options_.shape, bad), std::invalid_argument);
}

TEST(ShapeMessageConfigurationTest, QGoesInAndOutAndMustBeFinite) {
  shape_t message = ShapeToMessage(ShapeEstimate{});
  EXPECT_FALSE(message.has_configuration);
  EXPECT_FALSE(MessageConfiguration(message).has_value());
  const Configuration q(0.01, -0.02, 0.003, 0.004);
  SetMessageConfiguration(q, 0.05, &message);
  EXPECT_EQ(ValidateShapeMessage(message), "");
  EXPECT_EQ(MessageConfiguration(message), q);
  EXPECT_EQ(message.configuration_residual_mm, 0.05);
  message.q[2] = std::nan("");
  EXPECT_NE(ValidateShapeMessage(message).find('q'), std::string::npos);
  message.has_configuration = false;  // q is not read then
  EXPECT_EQ(ValidateShapeMessage(message), "");
}

TEST_F(ShapeConfigurationTest, TheSectionAndTheSetupMustAgree) {
  ShapeServiceOptions off = options_;
  off.configuration.enabled = false;
  EXPECT_THROW(ShapeService(off, rig_->rig(), bus_, setup_), std::invalid_argument);
  EXPECT_THROW(ShapeService(options_, rig_->rig(), bus_), std::invalid_argument);
}

class ShapeConfigurationFilesTest : public ::testing::Test {
 public:
  ~ShapeConfigurationFilesTest() override { fs::remove_all(dir_); }

 protected:
  ShapeConfigurationFilesTest()
      : dir_(fs::temp_directory_path() / ("shape_configuration_test_" + std::to_string(getpid()))) {
    fs::create_directories(dir_ / "models");
  }

  // A shape config in dir_ with the given configuration section; the model
  // (config/manipulator.yaml) at models/arm.yaml, referred to relatively.
  ServiceArgs Write(const ShapeConfigurationOptions& section, const std::string& model) {
    ShapeServiceOptions options;
    options.rig = "rig.yaml";
    options.shape.refine_with_silhouettes = false;
    options.configuration = section;
    options.configuration.manipulator = "models/arm.yaml";
    WriteFileAtomically(dir_ / "shape.yaml", OptionsToDocumentedYaml(options));
    WriteFileAtomically(dir_ / "models" / "arm.yaml", model);
    ServiceArgs args;
    args.config = dir_ / "shape.yaml";
    return args;
  }

  static std::string ShippedModel() {
    return ReadTextFile(fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "manipulator.yaml");
  }

  fs::path dir_;
};

TEST_F(ShapeConfigurationFilesTest, TheModelFileIsReadRelativeToTheConfig) {
  ShapeConfigurationOptions section;
  section.enabled = true;
  section.base.base_position = {1.0, 2.0, 3.0};
  section.base.base_rotation = {0.0, 0.0, std::numbers::pi / 2.0};
  const ShapeServiceOptions options = LoadShapeServiceOptions(Write(section, ShippedModel()));
  EXPECT_EQ(fs::path(options.configuration.manipulator), dir_ / "models" / "arm.yaml");
  const std::optional<ConfigurationSetup> setup = LoadConfigurationSetup(options);
  ASSERT_TRUE(setup.has_value());
  EXPECT_EQ(setup->geometry.rest.proximal, 600.0);
  EXPECT_EQ(setup->geometry.rest.distal, 160.0);
  // The rotation vector turns base x onto world y.
  EXPECT_LT((setup->geometry.world_from_base * Vec3(1, 0, 0) - Vec3(1, 3, 3)).norm(), 1e-12);
  section.enabled = false;
  EXPECT_FALSE(LoadConfigurationSetup(LoadShapeServiceOptions(Write(section, ShippedModel()))));
}

TEST_F(ShapeConfigurationFilesTest, BadModelsAndKeysAreNamed) {
  ShapeConfigurationOptions section;
  section.enabled = true;
  const auto error_of = [&](const ShapeConfigurationOptions& s, const std::string& model) {
    try {
      LoadConfigurationSetup(LoadShapeServiceOptions(Write(s, model)));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of(section, "proximal_length: -1\n").find("arm.yaml: proximal_length"),
            std::string::npos);
  ShapeConfigurationOptions long_band = section;
  long_band.tapes.distal_band_before_tip = 170.0;
  EXPECT_NE(error_of(long_band, ShippedModel()).find("configuration.tapes.distal_band_before_tip"),
            std::string::npos)
      << error_of(long_band, ShippedModel());
  ShapeConfigurationOptions bad = section;
  bad.sensing.max_strain = -1.0;
  EXPECT_NE(error_of(bad, ShippedModel()).find("configuration.sensing.max_strain"),
            std::string::npos);
  // Bands of the shape's band_width that the layout cannot carry apart.
  ShapeServiceOptions wide = LoadShapeServiceOptions(Write(section, ShippedModel()));
  const auto setup_error = [](const ShapeServiceOptions& o) {
    try {
      LoadConfigurationSetup(o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  wide.shape.band_width = 4.0;
  EXPECT_EQ(setup_error(wide), "");
  wide.shape.band_width = 24.0;  // the distal band is 10 mm before the tip
  EXPECT_NE(setup_error(wide).find("shape.band_width 24 mm: the distal band"), std::string::npos)
      << setup_error(wide);
  wide.configuration.tapes.proximal_band_before_junction = 15.0;
  wide.shape.band_width = 16.0;
  EXPECT_NE(setup_error(wide).find("wider than the spacing between them"), std::string::npos)
      << setup_error(wide);
  // Enabled without a model file.
  ShapeServiceOptions options = testing::TestShapeOptions();
  options.configuration.enabled = true;
  EXPECT_EQ(options.Validate().rfind("configuration.manipulator", 0), 0u) << options.Validate();
}

TEST(ShapeConfigurationShippedTest, TheShippedConfigDocumentsTheSectionWithItsDefaults) {
  ServiceArgs args;
  args.config = fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "shape_service.yaml";
  ShapeServiceOptions shipped = LoadShapeServiceOptions(args);
  EXPECT_FALSE(shipped.configuration.enabled);
  EXPECT_EQ(fs::path(shipped.configuration.manipulator).filename(), "manipulator.yaml");
  shipped.configuration.manipulator.clear();
  EXPECT_EQ(YAML::Dump(OptionsToYaml(shipped.configuration)),
            YAML::Dump(OptionsToYaml(ShapeConfigurationOptions{})));
  // Turned on, it reads the shipped model next to it.
  shipped = LoadShapeServiceOptions(args);
  shipped.configuration.enabled = true;
  const std::optional<ConfigurationSetup> setup = LoadConfigurationSetup(shipped);
  ASSERT_TRUE(setup.has_value());
  EXPECT_EQ(setup->geometry.rest.distal, 160.0);
}

}  // namespace
}  // namespace shapesense
