#pragma once

// A family of looks for the renderer: a test set for whatever reads the
// images (silhouettes, tape markers) that must not depend on the one look it
// was tuned on. Issue 16: an independent renderer's images differed from ours
// in the tape (a darker red, BGR 35,30,190, shaded 75-100 % across the tube),
// a near-black body, 5 mm bands, supersampled edges (the bands' too) and ±2 %
// exposure flicker, and the tape markers were lost there. The family spans
// those differences and more.
//
// Every look keeps what the silhouette extractor and the tape classifier can
// rely on, with margin:
//  - green: body and tape stay at least 60 grey levels below the
//    background's green (its vignetted corners) under the look's brightest
//    shading and exposure; light bodies get a brighter green screen for that;
//  - the tape is reddish: hue within 35° of red and saturation at least 0.4
//    in its unshaded colour (shading scales the channels together, so it
//    keeps hue and saturation; a phong highlight and noise lower them a little);
//  - the body is not: saturation below 0.25, or a hue far from red (bluish).
//    Near-black bodies have no reliable hue at all under noise: a classifier
//    needs a floor on value (brightness) to tell them from the tape.
//
// The looks, in order, and what each is for:
//  1. today's defaults: the reference every other look departs from;
//  2. the independent renderer's look (dark red, near-black, wrap, 5 mm,
//     supersampled, exposure 0.98), seen steeply;
//  3. orange-red tape (hue +22°) on mid grey, side light, level cameras;
//  4. crimson tape (hue -20°) with a white phong highlight, which lowers the
//     tape's saturation where it falls;
//  5. magenta-red tape (hue -32°, the edge of the red range) on light grey,
//     nearly along the shaft (70°), wide bands so they still show;
//  6. pale pink tape (saturation 0.45) on light grey: the saturation floor;
//  7. saturated red on a bluish body (saturated, but far in hue), 3 mm bands,
//     the most noise (3.5) and the brightest exposure (1.03);
//  8. the dark red again on mid grey with a strong highlight, 8 mm bands, level;
//  9. pale orange-red (salmon, saturation 0.48) on near black, the darkest exposure (0.97);
// 10. crimson on a bluish body, soft shading, light from the side;
// 11. red on near black, 8 mm bands, nearly along the shaft (70°);
// 12. orange-red on light grey with a broad highlight, steep (55°);
// 13. magenta-red, 3 mm bands on mid grey, light from below the horizontal;
// 14. pale pink on near black, soft shading lit from slightly below, level.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "libs/sim/tube_scene.h"

namespace shapesense {

struct Look {
  std::string name;      // what it shows, e.g. "dark-red tape, near-black body, wrap, 55 deg"
  RenderOptions render;  // body, backdrop, shading, light, exposure, noise, supersampling
  std::array<uint8_t, 3> tape_bgr = {30, 30, 200};  // every band's colour
  double band_width = 4.0;                          // every band's width along the tube, mm
  // Camera obliqueness to the shaft: the synthetic rig's elevation_deg
  // (SyntheticRigOptions), since RandomScene's tube starts along +z: 0 sees
  // the shaft from the side, 70 nearly along it.
  double elevation_deg = 20.0;
};

// The family above, the same on every call: 14 looks spanning tape hues from
// orange-red to magenta-red, saturated to pale, band widths 3-8 mm, near-black
// to light grey and bluish bodies, several light directions, the three
// shading models, exposure gains 0.97-1.03, supersampling 1 and 3, noise
// 1.5-3.5 and elevations 0, 20, 40, 55 and 70 degrees.
std::vector<Look> LookFamily();

// Gives every tape band of the scene the look's colour and width (centres unchanged).
void ApplyLook(const Look& look, TubeScene* scene);

}  // namespace shapesense
