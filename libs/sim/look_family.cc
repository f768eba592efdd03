#include "libs/sim/look_family.h"

namespace shapesense {
namespace {

// The green screen behind the tube. A light body needs a brighter screen:
// its green must stay 60 grey levels below the screen's at the corners.
enum class Screen {
  kStandard,  // RenderOptions' default: BGR 40,175,45, 15 % fall-off to the corners
  kBright,    // 50,220,55, 10 %
  kBrightest  // 60,250,65, 5 %
};

// One look, as its table row (the fields RenderOptions does not default as wanted).
struct LookSpec {
  const char* name;
  std::array<uint8_t, 3> tape;
  double band_width;
  std::array<double, 3> body;
  Screen screen = Screen::kStandard;
  const char* shading = "lambert";
  double ambient = 0.55;
  double diffuse = 0.6;
  double specular = 0.0;  // phong
  double shininess = 40.0;
  std::array<double, 3> light = {0.3, -0.5, 1.0};
  double exposure_gain = 1.0;
  int supersampling = 1;
  double noise_sigma = 2.0;
  double elevation_deg = 20.0;
};

void SetScreen(Screen screen, RenderOptions* options) {
  if (screen == Screen::kBright) {
    options->backdrop_bgr = {50.0, 220.0, 55.0};
    options->backdrop_vignette = 0.10;
  } else if (screen == Screen::kBrightest) {
    options->backdrop_bgr = {60.0, 250.0, 65.0};
    options->backdrop_vignette = 0.05;
  }
}

Look LookOf(const LookSpec& spec) {
  Look look;
  look.name = spec.name;
  look.tape_bgr = spec.tape;
  look.band_width = spec.band_width;
  look.elevation_deg = spec.elevation_deg;
  RenderOptions& render = look.render;
  SetScreen(spec.screen, &render);
  render.body_bgr = spec.body;
  render.shading = spec.shading;
  render.ambient = spec.ambient;
  render.diffuse = spec.diffuse;
  render.specular = spec.specular;
  render.shininess = spec.shininess;
  render.light_direction = spec.light;
  render.exposure_gain = spec.exposure_gain;
  render.supersampling = spec.supersampling;
  render.noise_sigma = spec.noise_sigma;
  return look;
}

// The header's list, in its order. Wrap looks light 70-100 % or 75-100 %
// (ambient, then diffuse the rest), as the independent renderer's tape was shaded.
constexpr LookSpec kLooks[] = {
    {.name = "red tape, grey body, lambert, 20 deg (today's defaults)",
     .tape = {30, 30, 200},
     .band_width = 4.0,
     .body = {60.0, 60.0, 65.0}},
    {.name = "dark-red tape, near-black body, wrap shading, 55 deg",
     .tape = {35, 30, 190},
     .band_width = 5.0,
     .body = {22.0, 22.0, 24.0},
     .shading = "wrap",
     .ambient = 0.75,
     .diffuse = 0.25,
     .light = {0.0, 0.0, 1.0},
     .exposure_gain = 0.98,
     .supersampling = 3,
     .noise_sigma = 2.5,
     .elevation_deg = 55.0},
    {.name = "orange-red tape, mid-grey body, lambert, side light, 0 deg",
     .tape = {10, 69, 170},
     .band_width = 6.0,
     .body = {110.0, 110.0, 110.0},
     .screen = Screen::kBright,
     .light = {1.0, 0.2, 0.3},
     .exposure_gain = 1.02,
     .noise_sigma = 3.0,
     .elevation_deg = 0.0},
    {.name = "crimson tape, near-black body, phong highlight, 40 deg",
     .tape = {83, 25, 200},
     .band_width = 5.0,
     .body = {30.0, 30.0, 30.0},
     .shading = "phong",
     .ambient = 0.5,
     .specular = 0.12,
     .light = {-0.4, 0.6, 1.0},
     .supersampling = 3,
     .elevation_deg = 40.0},
    {.name = "magenta-red tape, light-grey body, wrap shading, 70 deg",
     .tape = {126, 30, 210},
     .band_width = 7.0,
     .body = {170.0, 170.0, 170.0},
     .screen = Screen::kBrightest,
     .shading = "wrap",
     .ambient = 0.7,
     .diffuse = 0.3,
     .light = {0.5, 0.5, 0.7},
     .exposure_gain = 1.01,
     .supersampling = 3,
     .elevation_deg = 70.0},
    {.name = "pale pink tape, light-grey body, lambert, low side light, 20 deg",
     .tape = {145, 130, 235},
     .band_width = 5.0,
     .body = {150.0, 150.0, 150.0},
     .screen = Screen::kBrightest,
     .ambient = 0.5,
     .diffuse = 0.5,
     .light = {-1.0, -0.3, 0.4},
     .exposure_gain = 0.97},
    {.name = "red tape 3 mm, bluish body, lambert, noisy, 55 deg",
     .tape = {20, 20, 230},
     .band_width = 3.0,
     .body = {115.0, 70.0, 45.0},
     .light = {0.0, 0.8, 0.4},
     .exposure_gain = 1.03,
     .noise_sigma = 3.5,
     .elevation_deg = 55.0},
    {.name = "dark-red tape 8 mm, mid-grey body, phong highlight, 0 deg",
     .tape = {35, 30, 190},
     .band_width = 8.0,
     .body = {90.0, 90.0, 90.0},
     .screen = Screen::kBright,
     .shading = "phong",
     .ambient = 0.5,
     .diffuse = 0.55,
     .specular = 0.15,
     .shininess = 60.0,
     .light = {-0.6, -0.3, 0.7},
     .exposure_gain = 0.99,
     .supersampling = 3,
     .noise_sigma = 1.5,
     .elevation_deg = 0.0},
    {.name = "salmon (pale orange-red) tape, near-black body, wrap shading, 40 deg",
     .tape = {65, 80, 125},
     .band_width = 5.0,
     .body = {25.0, 25.0, 25.0},
     .shading = "wrap",
     .ambient = 0.75,
     .diffuse = 0.25,
     .light = {0.2, -1.0, 0.2},
     .exposure_gain = 0.97,
     .noise_sigma = 2.5,
     .elevation_deg = 40.0},
    {.name = "crimson tape, bluish body, wrap shading, side light, 20 deg",
     .tape = {80, 20, 185},
     .band_width = 4.0,
     .body = {110.0, 75.0, 60.0},
     .shading = "wrap",
     .ambient = 0.7,
     .diffuse = 0.3,
     .light = {0.8, 0.5, 0.3},
     .exposure_gain = 1.01,
     .supersampling = 3,
     .noise_sigma = 2.5},
    {.name = "red tape 8 mm, near-black body, lambert, 70 deg",
     .tape = {20, 45, 230},
     .band_width = 8.0,
     .body = {18.0, 18.0, 20.0},
     .exposure_gain = 0.99,
     .noise_sigma = 3.0,
     .elevation_deg = 70.0},
    {.name = "orange-red tape, light-grey body, phong highlight, 55 deg",
     .tape = {10, 75, 200},
     .band_width = 6.0,
     .body = {160.0, 160.0, 160.0},
     .screen = Screen::kBrightest,
     .shading = "phong",
     .ambient = 0.45,
     .diffuse = 0.45,
     .specular = 0.1,
     .shininess = 15.0,
     .light = {-0.3, 0.4, 1.0},
     .exposure_gain = 1.02,
     .supersampling = 3,
     .elevation_deg = 55.0},
    {.name = "magenta-red tape 3 mm, mid-grey body, lambert, light from below, 40 deg",
     .tape = {120, 35, 200},
     .band_width = 3.0,
     .body = {75.0, 75.0, 78.0},
     .ambient = 0.5,
     .diffuse = 0.55,
     .light = {-0.2, 0.9, -0.3},
     .noise_sigma = 1.5,
     .elevation_deg = 40.0},
    {.name = "pale pink tape, near-black body, wrap shading, light from below, 0 deg",
     .tape = {100, 80, 150},
     .band_width = 5.0,
     .body = {20.0, 20.0, 22.0},
     .shading = "wrap",
     .ambient = 0.7,
     .diffuse = 0.3,
     .light = {0.6, -0.6, -0.2},
     .exposure_gain = 1.03,
     .supersampling = 3,
     .elevation_deg = 0.0},
};

}  // namespace

std::vector<Look> LookFamily() {
  std::vector<Look> looks;
  for (const LookSpec& spec : kLooks) looks.push_back(LookOf(spec));
  return looks;
}

void ApplyLook(const Look& look, TubeScene* scene) {
  for (TapeBand& tape : scene->tapes) {
    tape.bgr = look.tape_bgr;
    tape.width = look.band_width;
  }
}

}  // namespace shapesense
