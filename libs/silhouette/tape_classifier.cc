#include "libs/silhouette/tape_classifier.h"

#include <stdexcept>

#include "libs/core/error.h"

namespace shapesense {
namespace {

std::string Hues(const std::array<double, 2>& hue_deg) {
  std::string text = "[";  // appended to: GCC 12 warns falsely on "[" + std::string
  text += Number(hue_deg[0]) + ", " + Number(hue_deg[1]) + "]";
  return text;
}

// The least chroma (max - min) that passes at each value (max); above the
// value (256 below min_value): none.
std::array<int16_t, 256> MinChroma(const TapeColour& colour) {
  std::array<int16_t, 256> min_chroma{};
  min_chroma.fill(256);
  for (int value = std::max(colour.min_value, 1); value < 256; ++value) {
    int chroma = 1;  // min_saturation > 0: grey never passes
    while (chroma <= value && static_cast<double>(chroma) / value < colour.min_saturation) ++chroma;
    min_chroma[value] = static_cast<int16_t>(chroma);
  }
  return min_chroma;
}

}  // namespace

std::string TapeColour::Validate() const {
  for (const double hue : hue_deg) {
    if (!(hue >= 0.0 && hue < 360.0)) {
      return Expected("hue_deg", "two hues [from, to] in [0, 360)", Hues(hue_deg));
    }
  }
  if (hue_deg[0] == hue_deg[1]) {
    return Expected("hue_deg", "two different hues [from, to] (from > to wraps through 0)",
                    Hues(hue_deg));
  }
  const Range saturations{0.0, 1.0, true, true};
  if (!saturations.Contains(min_saturation)) {
    return ExpectWithin("min_saturation", min_saturation, saturations);
  }
  if (min_value < 0 || min_value > 255) return Expected("min_value", "0-255", min_value);
  return {};
}

std::string Describe(const TapeColour& colour) {
  return Hues(colour.hue_deg) + "° (saturation ≥ " + Number(colour.min_saturation) + ", value ≥ " +
         std::to_string(colour.min_value) + ")";
}

double HueDeg(const uint8_t* bgr) {
  const int b = bgr[0], g = bgr[1], r = bgr[2];
  const int high = std::max({b, g, r});
  const int chroma = high - std::min({b, g, r});
  if (chroma == 0) return 0.0;
  double hue = 0.0;
  if (high == r) {
    hue = 60.0 * (g - b) / chroma;
  } else if (high == g) {
    hue = 60.0 * (b - r) / chroma + 120.0;
  } else {
    hue = 60.0 * (r - g) / chroma + 240.0;
  }
  return hue < 0.0 ? hue + 360.0 : hue;
}

double Saturation(const uint8_t* bgr) {
  const int high = std::max({bgr[0], bgr[1], bgr[2]});
  if (high == 0) return 0.0;
  return static_cast<double>(high - std::min({bgr[0], bgr[1], bgr[2]})) / high;
}

bool TapeColour::HueInRange(double hue) const {
  const double from = hue_deg[0];
  const double to = hue_deg[1];
  return from < to ? hue >= from && hue <= to : hue >= from || hue <= to;
}

TapeClassifier::TapeClassifier(const TapeColour& colour) {
  if (const std::string error = colour.Validate(); !error.empty()) {
    throw std::invalid_argument("TapeColour: " + error);
  }
  min_chroma_ = MinChroma(colour);
  hue_bits_ = HueBits(colour);
}

// Every difference pair that a colour can have, through its darkest colour
// (HueDeg reads only the differences).
std::vector<uint64_t> TapeClassifier::HueBits(const TapeColour& colour) {
  std::vector<uint64_t> bits((kDifferences * kDifferences + 63) / 64, 0);
  for (int green_red = -255; green_red <= 255; ++green_red) {
    for (int blue_red = -255; blue_red <= 255; ++blue_red) {
      const int r = std::max({0, -green_red, -blue_red});
      const int g = r + green_red, b = r + blue_red;
      if (g > 255 || b > 255) continue;
      const uint8_t bgr[3] = {static_cast<uint8_t>(b), static_cast<uint8_t>(g),
                              static_cast<uint8_t>(r)};
      if (!colour.HueInRange(HueDeg(bgr))) continue;
      const int index = (green_red + 255) * kDifferences + (blue_red + 255);
      bits[index >> 6] |= uint64_t{1} << (index & 63);
    }
  }
  return bits;
}

}  // namespace shapesense
