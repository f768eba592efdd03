#pragma once

// Which silhouette pixels are tape: a colour in a range of hues, saturated
// and bright enough (HSV as usual: value = max(B, G, R), saturation =
// (max - min) / max, hue in degrees in [0, 360) after the textbook formula).

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace shapesense {

struct TapeColour {
  // Hues [from, to], degrees in [0, 360), both included; from > to wraps
  // through 0 (330, 25: 330-360 and 0-25). The default takes reds from
  // crimson to orange-red and stops before the yellow that red tape mixed
  // with the green backdrop turns into at the silhouette's edge.
  std::array<double, 2> hue_deg = {335.0, 25.0};
  // Grey body and tape mixed with it keep a red hue at a low saturation.
  double min_saturation = 0.4;
  // Dark pixels have no reliable hue: noise of a few levels swings it.
  int min_value = 60;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("hue_deg", hue_deg, "hues [from, to], degrees in [0, 360); from > to wraps through 0");
    visit("min_saturation", min_saturation,
          "smallest saturation, (max - min) / max (0-1, both excluded)");
    visit("min_value", min_value, "smallest value, max(B, G, R) (0-255)");
  }
  std::string Validate() const;

  // Whether a hue (degrees, [0, 360)) lies in hue_deg, ends included.
  bool HueInRange(double hue) const;
};

// "[from, to]° (saturation ≥ s, value ≥ v)", for messages.
std::string Describe(const TapeColour& colour);

// The textbook HSV of a BGR pixel; hue 0 for greys (saturation 0).
double HueDeg(const uint8_t* bgr);
double Saturation(const uint8_t* bgr);

// TapeColour as two lookups without division, for the per-pixel loop: the
// chroma (max - min) against the least that passes at the pixel's value,
// then one bit by (g - r, b - r), which fix the hue. The bits are HueDeg's
// decisions, so IsTape decides every colour as the floating-point rule.
class TapeClassifier {
 public:
  // Throws std::invalid_argument when `colour` fails Validate().
  explicit TapeClassifier(const TapeColour& colour);

  bool IsTape(const uint8_t* bgr) const {
    const int b = bgr[0], g = bgr[1], r = bgr[2];
    const int high = std::max({b, g, r});
    // Most mask pixels are the grey body: decided by one lookup, and the
    // branch is predictable along a run of body or of tape.
    if (high - std::min({b, g, r}) < min_chroma_[high]) return false;
    const int index = (g - r + 255) * kDifferences + (b - r + 255);
    return ((hue_bits_[index >> 6] >> (index & 63)) & 1) != 0;
  }

 private:
  static constexpr int kDifferences = 511;  // -255..255
  static std::vector<uint64_t> HueBits(const TapeColour& colour);

  std::array<int16_t, 256> min_chroma_{};  // by value; an entry above its value: none passes
  // Bit (g - r + 255) × 511 + (b - r + 255): the hue is in range. 32 kB;
  // a tape's colours touch a few of its cache lines.
  std::vector<uint64_t> hue_bits_;
};

}  // namespace shapesense
