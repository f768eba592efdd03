#pragma once

// Synthetic camera frames of a tube on a green backdrop with known ground
// truth: which pixels are tube, tape, shadow and noise blob.

#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace shapesense::testing {

inline const cv::Scalar kBackdropBgr(40, 175, 45);
inline const cv::Scalar kTubeBgr(62, 64, 68);
inline const cv::Scalar kTapeBgr(40, 40, 200);

struct FrameSpec {
  cv::Size size{640, 480};
  int tube_thickness = 10;  // px
  double curl = 1.0;        // scales the bend of the curve
  int tape_bands = 3;
  double shadow_scale = 0.65;  // backdrop brightness in the shadow (1: no shadow)
  cv::Point shadow_offset{16, 12};
  int holes = 6;             // 1-2 px holes inside the tube that look like backdrop
  int blobs = 8;             // small dark blobs away from the tube, < 40 px each
  bool second_tube = false;  // a separate large object (say, a second tool)
  double noise_sigma = 2.0;
  unsigned seed = 1;
};

struct SyntheticFrame {
  cv::Mat image;       // CV_8UC3
  cv::Mat background;  // CV_8UC3, the backdrop alone
  cv::Mat tube;        // CV_8U 255: the tube (holes included), and the second tube if any
  cv::Mat tape;        // CV_8U 255: tape pixels (a subset of tube)
  cv::Mat shadow;      // CV_8U 255: backdrop pixels in (nearly) full shadow
  cv::Mat blobs;       // CV_8U 255: the noise blobs
  cv::Mat holes;       // CV_8U 255: tube pixels coloured as backdrop
};

// A long curve entering at the bottom edge and bending across the image.
inline std::vector<cv::Point> TubeCurve(const FrameSpec& spec) {
  std::vector<cv::Point> points;
  const double w = spec.size.width;
  const double h = spec.size.height;
  for (int i = 0; i <= 200; ++i) {
    const double t = i / 200.0;
    const double x = w * (0.2 + 0.6 * t + 0.08 * spec.curl * std::sin(6.0 * t));
    const double y = h * (1.05 - 0.85 * t) + 0.12 * h * spec.curl * std::sin(3.5 * t);
    points.emplace_back(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)));
  }
  return points;
}

inline void AddNoise(cv::Mat* image, double sigma, uint64_t seed) {
  cv::Mat noise(image->size(), CV_16SC3);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  cv::Mat noisy;
  image->convertTo(noisy, CV_16SC3);
  noisy += noise;
  noisy.convertTo(*image, CV_8UC3);  // saturates
}

inline void DrawTapeBands(const std::vector<cv::Point>& curve, const FrameSpec& spec,
                          SyntheticFrame* frame) {
  frame->tape = cv::Mat::zeros(spec.size, CV_8U);
  for (int band = 0; band < spec.tape_bands; ++band) {
    const size_t at = curve.size() * (band + 1) / (spec.tape_bands + 1);
    cv::circle(frame->tape, curve[at], spec.tube_thickness, cv::Scalar(255), cv::FILLED);
  }
  frame->tape &= frame->tube;
}

inline void DrawBlobs(const FrameSpec& spec, std::mt19937* rng, SyntheticFrame* frame) {
  frame->blobs = cv::Mat::zeros(spec.size, CV_8U);
  std::uniform_int_distribution<int> x(5, spec.size.width - 6);
  std::uniform_int_distribution<int> y(5, spec.size.height - 6);
  cv::Mat near_tube;
  cv::dilate(frame->tube, near_tube, cv::Mat(), cv::Point(-1, -1), 30);
  for (int placed = 0, tries = 0; placed < spec.blobs && tries < 1000; ++tries) {
    const cv::Point center(x(*rng), y(*rng));
    if (near_tube.at<uint8_t>(center) != 0) continue;
    cv::circle(frame->blobs, center, 1 + placed % 3, cv::Scalar(255), cv::FILLED);
    ++placed;
  }
}

inline void PunchHoles(const FrameSpec& spec, std::mt19937* rng, SyntheticFrame* frame,
                       cv::Mat* hole_mask) {
  *hole_mask = cv::Mat::zeros(spec.size, CV_8U);
  cv::Mat inner;
  cv::erode(frame->tube, inner, cv::Mat(), cv::Point(-1, -1), 3);
  std::vector<cv::Point> candidates;
  cv::findNonZero(inner, candidates);
  if (candidates.empty()) return;
  std::uniform_int_distribution<size_t> pick(0, candidates.size() - 1);
  for (int i = 0; i < spec.holes; ++i) {
    const cv::Point p = candidates[pick(*rng)];
    const cv::Size hole(1 + i % 2, 1 + (i / 2) % 2);  // 1×1 … 2×2
    (*hole_mask)(cv::Rect(p, hole) & cv::Rect(cv::Point(0, 0), spec.size)).setTo(255);
  }
}

// The frame: backdrop with a soft shadow, the tube with tape and holes, blobs, noise.
inline SyntheticFrame MakeFrame(const FrameSpec& spec) {
  std::mt19937 rng(spec.seed);
  SyntheticFrame frame;
  const std::vector<cv::Point> curve = TubeCurve(spec);
  frame.tube = cv::Mat::zeros(spec.size, CV_8U);
  cv::polylines(frame.tube, curve, false, cv::Scalar(255), spec.tube_thickness, cv::LINE_8);
  if (spec.second_tube) {
    cv::line(frame.tube, cv::Point(spec.size.width - 40, 20), cv::Point(spec.size.width - 40, 140),
             cv::Scalar(255), 8);
  }
  DrawTapeBands(curve, spec, &frame);
  DrawBlobs(spec, &rng, &frame);
  PunchHoles(spec, &rng, &frame, &frame.holes);
  const cv::Mat& holes = frame.holes;

  frame.background = cv::Mat(spec.size, CV_8UC3, kBackdropBgr);
  // Soft shadow: the tube shifted, blurred, darkening the backdrop.
  cv::Mat shifted = cv::Mat::zeros(spec.size, CV_32F);
  const cv::Mat shift =
      (cv::Mat_<double>(2, 3) << 1, 0, spec.shadow_offset.x, 0, 1, spec.shadow_offset.y);
  frame.tube.convertTo(shifted, CV_32F, 1.0 / 255.0);
  cv::warpAffine(shifted, shifted, shift, spec.size);
  cv::GaussianBlur(shifted, shifted, cv::Size(0, 0), 2.0);
  cv::Mat scale = 1.0 - (1.0 - spec.shadow_scale) * shifted;
  frame.shadow = (shifted > 0.9) & ~frame.tube;
  cv::Mat backdrop;
  frame.background.convertTo(backdrop, CV_32FC3);
  cv::Mat scale3;
  cv::merge(std::vector<cv::Mat>{scale, scale, scale}, scale3);
  backdrop = backdrop.mul(scale3);
  backdrop.convertTo(frame.image, CV_8UC3);

  frame.image.setTo(kTubeBgr, frame.tube & ~holes);
  frame.image.setTo(kTapeBgr, frame.tape & ~holes);
  frame.image.setTo(cv::Scalar(30, 30, 30), frame.blobs);
  AddNoise(&frame.image, spec.noise_sigma, 2 * spec.seed + 1);
  AddNoise(&frame.background, spec.noise_sigma, 2 * spec.seed + 2);
  return frame;
}

}  // namespace shapesense::testing
