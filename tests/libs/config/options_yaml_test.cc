#include "libs/config/options_yaml.h"

#include <gtest/gtest.h>

namespace shapesense {
namespace {

struct InnerOptions {
  std::array<double, 3> color = {1.0, 2.0, 3.0};
  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("color", color, "a colour");
  }
  std::string Validate() const { return color[0] < 0 ? "inner.color: expected >= 0" : ""; }
};

struct ExampleOptions {
  double voxel_size = 1.0;
  int levels = 3;
  bool enabled = true;
  std::string name = "default";
  std::vector<double> weights = {0.5};
  InnerOptions inner;
  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("voxel_size", voxel_size, "edge of one voxel, mm");
    visit("levels", levels, "hierarchy levels");
    visit("enabled", enabled, "on or off");
    visit("name", name, "a name");
    visit("weights", weights, "weights");
    visit("inner", inner, "nested options");
  }
  std::string Validate() const {
    if (!(voxel_size > 0))
      return "voxel_size: expected a positive number, got " + std::to_string(voxel_size);
    return inner.Validate();
  }
};

TEST(OptionsYamlTest, MissingKeysKeepTheirDefaults) {
  const auto options = OptionsFromYamlText<ExampleOptions>("levels: 5\n", "a.yaml");
  EXPECT_EQ(options.levels, 5);
  EXPECT_EQ(options.voxel_size, 1.0);
  EXPECT_EQ(options.name, "default");
}

TEST(OptionsYamlTest, EveryFieldRoundTrips) {
  ExampleOptions options;
  options.voxel_size = 0.25;
  options.levels = 7;
  options.enabled = false;
  options.name = "rig 2";
  options.weights = {1.5, -2.0, 3.25};
  options.inner.color = {9.0, 8.0, 7.5};
  YAML::Emitter emitter;
  emitter << OptionsToYaml(options);
  const auto parsed = OptionsFromYamlText<ExampleOptions>(emitter.c_str(), "round.yaml");
  EXPECT_EQ(parsed.voxel_size, options.voxel_size);
  EXPECT_EQ(parsed.levels, options.levels);
  EXPECT_EQ(parsed.enabled, options.enabled);
  EXPECT_EQ(parsed.name, options.name);
  EXPECT_EQ(parsed.weights, options.weights);
  EXPECT_EQ(parsed.inner.color, options.inner.color);
}

TEST(OptionsYamlTest, DocumentedYamlParsesBackToTheDefaults) {
  const std::string text = OptionsToDocumentedYaml(ExampleOptions{});
  EXPECT_NE(text.find("# edge of one voxel, mm"), std::string::npos);
  const auto parsed = OptionsFromYamlText<ExampleOptions>(text, "doc.yaml");
  EXPECT_EQ(parsed.inner.color, ExampleOptions{}.inner.color);
}

void ExpectError(const std::string& text, const std::string& fragment) {
  try {
    OptionsFromYamlText<ExampleOptions>(text, "cfg/carving.yaml");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(OptionsYamlTest, BadValuesNameFileKeyAndExpectation) {
  ExpectError("voxel_size: big\n", "cfg/carving.yaml: voxel_size: expected a number");
  ExpectError("voxel_size: -1\n", "cfg/carving.yaml: voxel_size: expected a positive number");
  ExpectError("levels: 2.5\n", "levels: expected an integer");
  ExpectError("voxl_size: 1\n", "voxl_size: unknown key");
  ExpectError("inner: {color: [1, 2]}\n", "inner.color: expected a sequence of 3");
  ExpectError("inner: {colour: [1, 2, 3]}\n", "inner.colour: unknown key");
  ExpectError("inner: {color: [-1, 2, 3]}\n", "inner.color: expected >= 0");
  ExpectError("enabled: maybe\n", "enabled: expected true or false");
  ExpectError("[1, 2]\n", "expected a map");
  ExpectError("a: [\n", "not valid YAML");
}

}  // namespace
}  // namespace shapesense

namespace shapesense {
namespace {

TEST(OptionsYamlTest, DocumentedYamlKeepsEveryDoubleExactly) {
  ExampleOptions options;
  options.voxel_size = 0.1 + 0.2;  // 0.30000000000000004: not 0.3
  options.weights = {1.0 / 3.0, 2568.0481234567891, 1e-17};
  const auto parsed =
      OptionsFromYamlText<ExampleOptions>(OptionsToDocumentedYaml(options), "doc.yaml");
  EXPECT_EQ(parsed.voxel_size, options.voxel_size);
  EXPECT_EQ(parsed.weights, options.weights);
  ExampleOptions plain;
  plain.voxel_size = 0.3;
  EXPECT_NE(OptionsToDocumentedYaml(plain).find("voxel_size: 0.3\n"), std::string::npos);
}

}  // namespace
}  // namespace shapesense
