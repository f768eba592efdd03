#include "libs/calibration/calibration_drawing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace shapesense {
namespace {

constexpr int kShift = 4;  // sub-pixel drawing: coordinates in 1/16 px
const cv::Scalar kGreen(60, 200, 60), kRed(40, 40, 230), kBlue(230, 120, 30), kYellow(0, 220, 255);
const cv::Scalar kBlack(0, 0, 0), kGrey(150, 150, 150), kWhite(255, 255, 255);

cv::Point Fixed(const Vec2& p) {
  return {static_cast<int>(std::lround(p.x() * (1 << kShift))),
          static_cast<int>(std::lround(p.y() * (1 << kShift)))};
}

cv::Point Pixel(const Vec2& p) {
  return {static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y()))};
}

std::string Format(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

void Caption(cv::Mat& image, const std::string& text, cv::Point where, double scale = 0.5,
             const cv::Scalar& colour = kBlack) {
  cv::putText(image, text, where, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

// White text on a dark band, readable over any image.
void Banner(cv::Mat& image, const std::string& text, int row, const cv::Scalar& colour) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.5, 1, &baseline);
  cv::rectangle(image, cv::Rect(0, row, size.width + 12, size.height + 10), kBlack, cv::FILLED);
  Caption(image, text, cv::Point(6, row + size.height + 4), 0.5, colour);
}

cv::Mat ToBgr(const cv::Mat& image) {
  cv::Mat bgr;
  if (image.channels() == 1) {
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  } else {
    bgr = image.clone();
  }
  return bgr;
}

// A "nice" number (1, 2 or 5 times a power of ten) at or above value.
double NiceCeil(double value) {
  if (!(value > 0.0)) return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (const double step : {1.0, 2.0, 5.0, 10.0}) {
    if (step * power >= value) return step * power;
  }
  return 10.0 * power;
}

struct Panel {
  cv::Rect box;
  double scale;  // px per mm
};

void DrawErrorBars(cv::Mat& canvas, const Panel& panel, const PointRegistration& registration) {
  const cv::Rect& box = panel.box;
  const int zero_y = box.y + box.height / 2;
  const double limit = box.height / 2.0 / panel.scale;
  for (const double fraction : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
    const int y = zero_y - static_cast<int>(std::lround(fraction * box.height / 2.0));
    cv::line(canvas, {box.x, y}, {box.x + box.width, y}, fraction == 0.0 ? kBlack : kGrey, 1);
    Caption(canvas, Format("%+.2f", fraction * limit), {box.x - 58, y + 4}, 0.4);
  }
  const size_t n = registration.errors.size();
  const double group = static_cast<double>(box.width) / static_cast<double>(n);
  const double bar = std::max(1.0, group / 5.0);
  for (size_t i = 0; i < n; ++i) {
    const Vec3& e = registration.errors[i];
    const double values[4] = {e.x(), e.y(), e.z(), e.norm()};
    const cv::Scalar colours[4] = {kRed, kGreen, kBlue, kGrey};
    for (int k = 0; k < 4; ++k) {
      const double left = box.x + group * static_cast<double>(i) + bar * (k + 0.5);
      const double top = zero_y - std::clamp(values[k], -limit, limit) * panel.scale;
      cv::rectangle(canvas, Fixed({left, std::min<double>(top, zero_y)}),
                    Fixed({left + bar - 1.0, std::max<double>(top, zero_y)}), colours[k],
                    cv::FILLED, cv::LINE_8, kShift);
    }
    if (n <= 40 || i % 5 == 0) {
      Caption(canvas, std::to_string(i + 1),
              {static_cast<int>(box.x + group * (i + 0.3)), box.y + box.height + 16}, 0.35);
    }
  }
}

void DrawTopView(cv::Mat& canvas, const cv::Rect& box, const std::vector<Vec3>& reference,
                 const PointRegistration& registration) {
  Vec2 low(reference[0].x(), reference[0].y()), high = low;
  double largest_error = 1e-9;
  for (size_t i = 0; i < reference.size(); ++i) {
    low = low.cwiseMin(reference[i].head<2>());
    high = high.cwiseMax(reference[i].head<2>());
    largest_error = std::max(largest_error, registration.errors[i].head<2>().norm());
  }
  const double span = std::max((high - low).maxCoeff(), 1e-6);
  const double scale = 0.8 * std::min(box.width, box.height) / span;  // px per mm
  const double magnify = NiceCeil(0.12 * std::min(box.width, box.height) / (largest_error * scale));
  const Vec2 centre(box.x + box.width / 2.0, box.y + box.height / 2.0);
  const auto to_canvas = [&](const Vec2& p) {
    const Vec2 d = (p - 0.5 * (low + high)) * scale;
    return Vec2(centre.x() + d.x(), centre.y() - d.y());  // y up
  };
  cv::rectangle(canvas, box, kGrey, 1);
  for (size_t i = 0; i < reference.size(); ++i) {
    const Vec2 at = to_canvas(reference[i].head<2>());
    const Vec2 error = magnify * registration.errors[i].head<2>();
    cv::circle(canvas, Fixed(at), 4 << kShift, kBlack, 1, cv::LINE_AA, kShift);
    cv::arrowedLine(canvas, Fixed(at), Fixed(to_canvas(reference[i].head<2>() + error)), kRed, 1,
                    cv::LINE_AA, kShift, 0.2);
  }
  Caption(canvas, "top view (x right, y up), errors x" + Format("%g", magnify), {box.x, box.y - 8});
  Caption(canvas, Format("x %.0f", low.x()) + Format(" .. %.0f mm", high.x()),
          {box.x, box.y + box.height + 16}, 0.4);
  Caption(canvas, Format("y %.0f", low.y()) + Format(" .. %.0f mm", high.y()),
          {box.x + box.width / 2, box.y + box.height + 16}, 0.4);
}

}  // namespace

cv::Mat DrawCornerOverlay(const cv::Mat& image, const BoardObservation& detected,
                          const std::vector<Vec2>& reprojected, const std::string& caption,
                          bool left_out, double error_scale) {
  cv::Mat canvas = ToBgr(image);
  for (size_t i = 0; i < detected.size(); ++i) {
    cv::circle(canvas, Fixed(detected.pixels[i]), 4 << kShift, kGreen, 1, cv::LINE_AA, kShift);
    if (i < reprojected.size()) {
      const Vec2 magnified =
          detected.pixels[i] + error_scale * (reprojected[i] - detected.pixels[i]);
      cv::line(canvas, Fixed(detected.pixels[i]), Fixed(magnified), kYellow, 1, cv::LINE_AA,
               kShift);
      cv::drawMarker(canvas, Pixel(reprojected[i]), kRed, cv::MARKER_CROSS, 7, 1);
    }
  }
  if (detected.size() >= 2) {
    cv::circle(canvas, Fixed(detected.pixels[0]), 8 << kShift, kBlue, 2, cv::LINE_AA, kShift);
    cv::arrowedLine(canvas, Pixel(detected.pixels[0]), Pixel(detected.pixels[1]), kBlue, 1,
                    cv::LINE_AA);
  }
  Banner(canvas, caption, 0, kWhite);
  if (left_out) {
    cv::rectangle(canvas, cv::Rect(0, 0, canvas.cols, canvas.rows), kRed, 6);
    Banner(canvas, "LEFT OUT: spoils the fit", 26, kRed);
  }
  return canvas;
}

cv::Mat DrawRegistrationPlot(const std::vector<Vec3>& reference,
                             const PointRegistration& registration) {
  cv::Mat canvas(460, 1000, CV_8UC3, kWhite);
  if (reference.empty() || registration.errors.size() != reference.size()) return canvas;
  double largest = 1e-9;
  for (const Vec3& e : registration.errors) largest = std::max(largest, e.norm());
  const Panel bars{cv::Rect(70, 50, 520, 360), 180.0 / NiceCeil(largest)};
  DrawErrorBars(canvas, bars, registration);
  const Vec3& rms = registration.rms_per_axis;
  Caption(canvas,
          "error per point, mm: x (red) y (green) z (blue) 3-D (grey); RMS x " +
              Format("%.3f", rms.x()) + Format(" y %.3f", rms.y()) + Format(" z %.3f", rms.z()) +
              Format(" 3-D %.3f", registration.rms),
          {10, 24}, 0.45);
  Caption(canvas, "point", {bars.box.x + bars.box.width / 2, bars.box.y + bars.box.height + 36},
          0.4);
  DrawTopView(canvas, cv::Rect(640, 50, 340, 360), reference, registration);
  return canvas;
}

}  // namespace shapesense
