// `shapesense tape-colour`: a rendered calibration image and background
// written to a folder, learnt through RunTapeColour and through the
// executable; bad input (a missing file, a prior window matching nothing, a
// bad config key) a clear message and exit code 2.
#include "clients/tools/tape_colour/tape_colour_command.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "libs/sim/tube_scene.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace {
namespace fs = std::filesystem;

const std::array<uint8_t, 3> kCrimson = {70, 20, 200};  // hue 343°

class TapeColourCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("shapesense_tape_colour_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    SyntheticRigOptions rig_options;
    rig_options.num_cameras = 1;
    const Rig rig = MakeSyntheticRig(rig_options);
    TubeScene scene = RandomScene(rig, 4, 1.5, 4);
    for (TapeBand& tape : scene.tapes) tape.bgr = kCrimson;
    const RenderedView view = RenderScene(rig, scene, RenderOptions{}, 4)[0];
    ASSERT_TRUE(cv::imwrite((dir_ / "image.png").string(), view.image));
    ASSERT_TRUE(cv::imwrite((dir_ / "background.png").string(), view.background));
    args_.image = dir_ / "image.png";
    args_.background = dir_ / "background.png";
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string RunError() {
    std::ostringstream out;
    try {
      RunTapeColour(args_, out);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no InputError)";
  }

  // Runs the executable; returns its exit code, its output in `out` and `err`.
  int RunExecutable(const std::string& arguments, std::string* out, std::string* err) const {
    const std::string command = std::string(SHAPESENSE_BINARY) + " tape-colour " + arguments +
                                " > " + (dir_ / "out.txt").string() + " 2> " +
                                (dir_ / "err.txt").string();
    const int status = std::system(command.c_str());
    *out = ReadTextFile(dir_ / "out.txt");
    *err = ReadTextFile(dir_ / "err.txt");
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  fs::path dir_;
  TapeColourArgs args_;
};

TEST_F(TapeColourCommandTest, PrintsTheLearntColourAsASilhouetteSectionToPaste) {
  std::ostringstream out;
  const LearntTapeColour learnt = RunTapeColour(args_, out);
  EXPECT_TRUE(learnt.colour.HueInRange(HueDeg(kCrimson.data()))) << out.str();
  EXPECT_FALSE(learnt.colour.HueInRange(0.0)) << "crimson's range should have left red";
  // Pasted into a config, the snippet gives the learnt colour and the
  // defaults for the rest.
  const YAML::Node snippet = YAML::Load(out.str());
  const SilhouetteOptions pasted =
      OptionsFromYaml<SilhouetteOptions>(snippet["silhouette"], "snippet");
  EXPECT_EQ(pasted.tape.hue_deg, learnt.colour.hue_deg);
  EXPECT_EQ(pasted.tape.min_saturation, learnt.colour.min_saturation);
  EXPECT_EQ(pasted.tape.min_value, learnt.colour.min_value);
  EXPECT_EQ(pasted.threshold, SilhouetteOptions{}.threshold);
  EXPECT_NE(out.str().find(std::to_string(learnt.pixels) + " pixels of the tape"),
            std::string::npos)
      << out.str();
  EXPECT_NE(out.str().find("it labels " + std::to_string(learnt.labelled) +
                           " of the silhouette's " + std::to_string(learnt.silhouette)),
            std::string::npos)
      << out.str();
}

TEST_F(TapeColourCommandTest, TheConfigsSilhouetteSectionIsThePrior) {
  args_.config = dir_ / "pipeline.yaml";
  WriteFileAtomically(args_.config,
                      "silhouette:\n  tape:\n    hue_deg: [200, 260]\ncarving:\n  voxel_size: 2\n");
  EXPECT_EQ(RunError().rfind("the tape hue range [200, 260]° (saturation ≥ 0.4, value ≥ 60) "
                             "matches no pixel of the silhouette",
                             0),
            0u)
      << RunError();
  WriteFileAtomically(args_.config, "silhouette:\n  tape:\n    hue: [330, 10]\n");
  EXPECT_EQ(RunError(), args_.config.string() + ": silhouette: tape.hue: unknown key");
  WriteFileAtomically(args_.config, "carving:\n  voxel_size: 2\n");  // no section: the defaults
  std::ostringstream out;
  EXPECT_NO_THROW(RunTapeColour(args_, out));
}

TEST_F(TapeColourCommandTest, MissingOrMismatchedPicturesAreNamed) {
  args_.image = dir_ / "nowhere.png";
  EXPECT_EQ(RunError(), "--image " + (dir_ / "nowhere.png").string() + ": missing");
  args_.image = dir_ / "image.png";
  ASSERT_TRUE(cv::imwrite((dir_ / "small.png").string(), cv::Mat(10, 20, CV_8UC3)));
  args_.background = dir_ / "small.png";
  const std::string error = RunError();
  EXPECT_NE(error.find("the background is 20x10"), std::string::npos) << error;
}

TEST_F(TapeColourCommandTest, TheExecutablePrintsTheSnippetOrExitsTwoWithTheMessage) {
  const std::string pictures =
      "--image " + args_.image.string() + " --background " + args_.background.string();
  std::string out, err;
  EXPECT_EQ(RunExecutable(pictures, &out, &err), 0) << err;
  EXPECT_NE(out.find("silhouette:\n  # tape colour"), std::string::npos) << out;
  EXPECT_EQ(err, "");

  EXPECT_EQ(RunExecutable("--image " + (dir_ / "nowhere.png").string() + " --background " +
                              args_.background.string(),
                          &out, &err),
            2);
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "shapesense: error: --image " + (dir_ / "nowhere.png").string() + ": missing\n");

  WriteFileAtomically(dir_ / "blue.yaml", "silhouette:\n  tape:\n    hue_deg: [200, 260]\n");
  EXPECT_EQ(RunExecutable(pictures + " --config " + (dir_ / "blue.yaml").string(), &out, &err), 2);
  EXPECT_NE(err.find("matches no pixel of the silhouette"), std::string::npos) << err;
}

}  // namespace
}  // namespace shapesense
