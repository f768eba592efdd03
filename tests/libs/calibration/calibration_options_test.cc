// The calibration options as YAML: every documented field reads back, and a
// bad value is refused naming its key.
#include <gtest/gtest.h>

#include "libs/calibration/calibration_board.h"
#include "libs/calibration/extrinsics.h"
#include "libs/calibration/intrinsics.h"
#include "libs/calibration/point_registration.h"
#include "libs/calibration/synthetic_board.h"
#include "libs/config/options_yaml.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

template <class Options>
void ExpectRoundTrip(const Options& options) {
  YAML::Emitter emitter;
  emitter << OptionsToYaml(options);
  const Options back = OptionsFromYamlText<Options>(emitter.c_str(), "options.yaml");
  YAML::Emitter again;
  again << OptionsToYaml(back);
  EXPECT_EQ(std::string(emitter.c_str()), std::string(again.c_str()));
  EXPECT_NE(OptionsToDocumentedYaml(options).find("# "), std::string::npos);
}

TEST(CalibrationOptionsTest, NonDefaultValuesRoundTripThroughYaml) {
  BoardOptions board;
  board.pattern = "charuco";
  board.cols = 7;
  board.square = 30.0;
  ExpectRoundTrip(board);
  IntrinsicsOptions intrinsics;
  intrinsics.fix_k3 = true;
  intrinsics.outlier_factor = 4.0;
  ExpectRoundTrip(intrinsics);
  ExtrinsicsOptions extrinsics;
  extrinsics.anchor_view = 3;
  extrinsics.refine_intrinsics = true;
  ExpectRoundTrip(extrinsics);
  RegistrationOptions registration;
  registration.loss_scale = 1.5;
  ExpectRoundTrip(registration);
  BoardRenderOptions render;
  render.seed = 17;
  ExpectRoundTrip(render);
}

TEST(CalibrationOptionsTest, BadValuesAreRefusedNamingTheirKey) {
  const auto error_of = [](auto parse) -> std::string {
    try {
      parse();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of([] { OptionsFromYamlText<BoardOptions>("cols: 1\n", "b.yaml"); }).find("cols"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              OptionsFromYamlText<ExtrinsicsOptions>("anchor_view: -1\n", "e.yaml");
            }).find("anchor_view"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              OptionsFromYamlText<IntrinsicsOptions>("min_views: 2\n", "i.yaml");
            }).find("min_views"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              OptionsFromYamlText<BoardRenderOptions>("dark: 300\n", "r.yaml");
            }).find("dark"),
            std::string::npos);
}

}  // namespace
}  // namespace shapesense
