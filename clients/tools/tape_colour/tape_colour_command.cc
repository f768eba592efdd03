#include "clients/tools/tape_colour/tape_colour_command.h"

#include <cmath>
#include <iostream>
#include <memory>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"

namespace shapesense {
namespace {

// The config's `silhouette` section; the defaults without a config or
// without the section (every key is optional). Other sections are not read:
// the file may be any config that holds one.
SilhouetteOptions LoadSilhouetteOptions(const std::filesystem::path& config) {
  if (config.empty()) return {};
  YAML::Node root;
  try {
    root = YAML::Load(ReadTextFile(config));
  } catch (const YAML::Exception& e) {
    throw InputError(config.string() + ": not valid YAML: " + e.what());
  }
  if (root && !root.IsNull() && !root.IsMap()) {
    throw InputError(config.string() + ": (top level): expected a map");
  }
  const YAML::Node section = root.IsMap() ? root["silhouette"] : YAML::Node();
  return OptionsFromYaml<SilhouetteOptions>(section, config.string() + ": silhouette");
}

// "--image path: missing": the option as well as the file.
cv::Mat ReadPicture(const std::string& option, const std::filesystem::path& path) {
  try {
    return ReadBgrImage(path);
  } catch (const InputError& e) {
    throw InputError(option + " " + e.what());
  }
}

void CheckSameSize(const cv::Mat& image, const cv::Mat& background, const TapeColourArgs& args) {
  if (image.size() == background.size()) return;
  throw InputError(args.background.string() + ": the background is " +
                   std::to_string(background.cols) + "x" + std::to_string(background.rows) +
                   ", the image " + args.image.string() + " " + std::to_string(image.cols) + "x" +
                   std::to_string(image.rows));
}

// The `tape` key's documentation, as the config files print it.
std::string TapeKeyDoc() {
  std::string doc;
  SilhouetteOptions options;
  options.VisitFields([&doc](const std::string& key, auto&, const char* text) {
    if (key == "tape") doc = text;
  });
  return doc;
}

}  // namespace

std::string FormatLearntTapeColour(const LearntTapeColour& learnt, const TapeColourArgs& args) {
  std::string text = "# tape colour learnt from " + args.image.string() + " (background " +
                     args.background.string() + "): " + std::to_string(learnt.pixels) +
                     " pixels of the tape, peak hue " +
                     Number(std::round(10.0 * learnt.peak_hue_deg) / 10.0) + "°\n";
  text += "# it labels " + std::to_string(learnt.labelled) + " of the silhouette's " +
          std::to_string(learnt.silhouette) + " pixels tape\n";
  text += "silhouette:\n  # " + TapeKeyDoc() + "\n  tape:\n" +
          OptionsToDocumentedYaml(learnt.colour, 4);
  return text;
}

LearntTapeColour RunTapeColour(const TapeColourArgs& args, std::ostream& out) {
  const SilhouetteOptions options = LoadSilhouetteOptions(args.config);
  const cv::Mat image = ReadPicture("--image", args.image);
  const cv::Mat background = ReadPicture("--background", args.background);
  CheckSameSize(image, background, args);
  const LearntTapeColour learnt = LearnTapeColour(image, background, options);
  out << FormatLearntTapeColour(learnt, args);
  return learnt;
}

void AddTapeColourCommand(CLI::App& app) {
  auto args = std::make_shared<TapeColourArgs>();
  CLI::App* command = app.add_subcommand(
      "tape-colour",
      "Learn the tape's colour (hue range, saturation and value minima) from a calibration image "
      "(docs/calibration.md)");
  command->add_option("--image", args->image, "picture of the manipulator with its tape in view")
      ->required();
  command->add_option("--background", args->background, "the same camera's background picture")
      ->required();
  command->add_option(
      "--config", args->config,
      "config with a silhouette section (config/pipeline.yaml, "
      "config/carving_service.yaml): its options, its tape colour the prior window");
  command->callback([args] { RunTapeColour(*args, std::cout); });
}

}  // namespace shapesense
