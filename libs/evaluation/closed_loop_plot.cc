#include "libs/evaluation/closed_loop_plot.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

constexpr int kWidth = 1400;
constexpr int kHeight = 700;
constexpr int kTitleHeight = 40;
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(225, 225, 225);
// Orange, blue, green, purple, red, brown: one per run, in order.
const std::vector<cv::Scalar> kRunColours = {{0, 130, 255},  {190, 90, 20}, {60, 160, 40},
                                             {160, 60, 140}, {40, 40, 200}, {40, 90, 140}};

cv::Scalar RunColour(size_t run) { return kRunColours[run % kRunColours.size()]; }

std::string Text(double value, int precision) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << value;
  return out.str();
}

// The shortest text of a tick value (0.01, 0.5, 20).
std::string TickText(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << (std::abs(value) < 1e-9 ? 0.0 : value);
  return out.str();
}

void PutText(cv::Mat& image, const std::string& text, cv::Point at, const cv::Scalar& colour,
             double size = 0.45) {
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, size, colour, 1, cv::LINE_AA);
}

// Text whose right end, or centre, is at `at`.
void PutTextAligned(cv::Mat& image, const std::string& text, cv::Point at, double align) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &baseline);
  at.x -= static_cast<int>(std::lround(align * size.width));
  PutText(image, text, at, kInk, 0.4);
}

// Shrinks the text as needed to fit `width` pixels (many runs, long modes).
void PutTextWithin(cv::Mat& image, const std::string& text, cv::Point at, int width, double size) {
  int baseline = 0;
  const int natural = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, size, 1, &baseline).width;
  PutText(image, text, at, kInk, natural > width ? size * width / natural : size);
}

void DashedLine(cv::Mat& image, cv::Point from, cv::Point to, const cv::Scalar& colour) {
  const double length = cv::norm(to - from);
  constexpr double kDash = 8.0;
  for (double s = 0.0; s < length; s += 2.0 * kDash) {
    const double e = std::min(s + kDash, length);
    const auto at = [&](double t) { return from + (to - from) * (t / length); };
    cv::line(image, at(s), at(e), colour, 1, cv::LINE_AA);
  }
}

// A 1-2-5 step giving about `count` intervals over `span`.
double NiceStep(double span, int count) {
  const double raw = span / count;
  const double decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double factor : {1.0, 2.0, 5.0}) {
    if (factor * decade >= raw) return factor * decade;
  }
  return 10.0 * decade;
}

// One axis, value to pixel, linear or log10.
struct Axis {
  double low = 0.0, high = 1.0;  // values at the ends
  int pixel_low = 0, pixel_high = 1;
  bool log = false;

  double Fraction(double value) const {
    if (log) return (std::log10(value) - std::log10(low)) / (std::log10(high) - std::log10(low));
    return (value - low) / (high - low);
  }
  int ToPixel(double value) const {
    return static_cast<int>(std::lround(pixel_low + Fraction(value) * (pixel_high - pixel_low)));
  }
};

// Each run's colour and mode in a row from `at`; returns where the row ends.
cv::Point DrawLegend(cv::Mat& panel, const std::vector<ExperimentPlotRun>& runs, cv::Point at) {
  for (size_t i = 0; i < runs.size(); ++i) {
    cv::line(panel, at + cv::Point(0, -4), at + cv::Point(22, -4), RunColour(i), 2, cv::LINE_AA);
    PutText(panel, runs[i].mode, at + cv::Point(28, 0), kInk);
    int baseline = 0;
    at.x += 50 + cv::getTextSize(runs[i].mode, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline).width;
  }
  return at;
}

// ---- left: tip paths looking down the shaft ----

struct TopView {
  Axis x, z;  // base frame x to the right, z up
  cv::Point ToPixel(const Vec3& p) const { return {x.ToPixel(p.x()), z.ToPixel(p.z())}; }
};

// Equal scale on both axes, fitted to `points` inside `area`, with a margin.
TopView FitTopView(const std::vector<Vec3>& points, const cv::Rect& area) {
  Vec2 low(-1.0, -1.0), high(1.0, 1.0);
  for (const Vec3& p : points) {
    if (!p.allFinite()) continue;  // a broken sample must not blank the view
    low = low.cwiseMin(Vec2(p.x(), p.z()));
    high = high.cwiseMax(Vec2(p.x(), p.z()));
  }
  const Vec2 centre = 0.5 * (low + high);
  const double scale =
      std::min(area.width / (high.x() - low.x()), area.height / (high.y() - low.y())) / 1.08;
  const Vec2 half = 0.5 * Vec2(area.width, area.height) / scale;
  TopView view;
  view.x = {centre.x() - half.x(), centre.x() + half.x(), area.x, area.x + area.width};
  view.z = {centre.y() - half.y(), centre.y() + half.y(), area.y + area.height, area.y};
  return view;
}

void DrawTopViewGrid(cv::Mat& panel, const TopView& view, const cv::Rect& area) {
  const double step = NiceStep(std::max(view.x.high - view.x.low, view.z.high - view.z.low), 8);
  for (double x = std::ceil(view.x.low / step) * step; x <= view.x.high; x += step) {
    const int u = view.x.ToPixel(x);
    cv::line(panel, {u, area.y}, {u, area.br().y}, kGrid);
    PutTextAligned(panel, TickText(x), {u, area.br().y + 16}, 0.5);
  }
  for (double z = std::ceil(view.z.low / step) * step; z <= view.z.high; z += step) {
    const int v = view.z.ToPixel(z);
    cv::line(panel, {area.x, v}, {area.br().x, v}, kGrid);
    PutTextAligned(panel, TickText(z), {area.x - 5, v + 4}, 1.0);
  }
  cv::rectangle(panel, area, kInk);
  PutTextAligned(panel, "x, mm", {area.x + area.width / 2, area.br().y + 36}, 0.5);
  PutText(panel, "z, mm", {area.x, area.y - 8}, kInk, 0.4);
}

void DrawTargetTips(cv::Mat& panel, const TopView& view, const std::vector<Vec3>& tips) {
  for (size_t i = 0; i < tips.size(); ++i) {
    const cv::Point at = view.ToPixel(tips[i]);
    cv::circle(panel, at, 5, kInk, 1, cv::LINE_AA);
    cv::drawMarker(panel, at, kInk, cv::MARKER_CROSS, 6, 1);
    PutText(panel, std::to_string(i + 1), at + cv::Point(6, -6), kInk, 0.4);
  }
}

cv::Mat DrawTipPanel(const std::vector<Vec3>& target_tips,
                     const std::vector<ExperimentPlotRun>& runs, cv::Size size) {
  cv::Mat panel(size, CV_8UC3, kWhite);
  const cv::Rect area(70, 70, size.width - 90, size.height - 120);
  std::vector<Vec3> everything = target_tips;
  for (const ExperimentPlotRun& run : runs) {
    everything.insert(everything.end(), run.tip_path.begin(), run.tip_path.end());
  }
  const TopView view = FitTopView(everything, area);
  DrawTopViewGrid(panel, view, area);
  for (size_t i = 0; i < runs.size(); ++i) {
    std::vector<cv::Point> pixels;
    for (const Vec3& p : runs[i].tip_path) pixels.push_back(view.ToPixel(p));
    cv::polylines(panel, pixels, false, RunColour(i), 1, cv::LINE_AA);
  }
  DrawTargetTips(panel, view, target_tips);
  PutText(panel, "true tip, looking down the shaft from the base (x right, z up)", {10, 20}, kInk,
          0.5);
  const cv::Point legend_end = DrawLegend(panel, runs, {90, 42});
  cv::circle(panel, legend_end + cv::Point(6, -4), 5, kInk, 1, cv::LINE_AA);
  PutText(panel, "target tips, in order", legend_end + cv::Point(18, 0), kInk);
  return panel;
}

// ---- right: steady-state error per target ----

// Decades covering every error and 1 mm; zero errors sit on the floor.
Axis FitErrorAxis(const std::vector<ExperimentPlotRun>& runs, const cv::Rect& area) {
  double low = 1.0, high = 1.0;
  for (const ExperimentPlotRun& run : runs) {
    if (run.score == nullptr) continue;
    for (const TargetScore& t : run.score->targets) {
      if (t.samples == 0 || !(t.tip_error_mm > 0.0) || !std::isfinite(t.tip_error_mm)) continue;
      low = std::min(low, t.tip_error_mm);
      high = std::max(high, t.tip_error_mm);
    }
  }
  const double floor = std::max(1e-3, std::pow(10.0, std::floor(std::log10(low))));
  const double ceiling = std::pow(10.0, std::ceil(std::log10(high * 1.0001)));
  return {std::min(floor, 0.1), std::max(ceiling, 10.0), area.br().y, area.y, true};
}

void DrawErrorGrid(cv::Mat& panel, const Axis& axis, const cv::Rect& area) {
  for (double decade = axis.low; decade <= axis.high * 1.0001; decade *= 10.0) {
    for (int m = 1; m < 10 && m * decade <= axis.high * 1.0001; ++m) {
      const int v = axis.ToPixel(m * decade);
      cv::line(panel, {area.x, v}, {area.br().x, v}, m == 1 ? cv::Scalar(200, 200, 200) : kGrid);
    }
    PutTextAligned(panel, TickText(decade), {area.x - 5, axis.ToPixel(decade) + 4}, 1.0);
  }
  cv::rectangle(panel, area, kInk);
  PutText(panel, "tip error, mm (log scale)", {area.x, area.y - 8}, kInk, 0.4);
  PutTextAligned(panel, "target", {area.x + area.width / 2, area.br().y + 36}, 0.5);
}

// Over the bars, the label on white so a bar cannot hide it.
void DrawOneMillimetreLine(cv::Mat& panel, const Axis& axis, const cv::Rect& area) {
  const cv::Scalar red(0, 0, 200);
  const int one = axis.ToPixel(1.0);
  DashedLine(panel, {area.x, one}, {area.br().x, one}, red);
  const cv::Point label(area.br().x - 42, one - 6);
  cv::rectangle(panel, label + cv::Point(-3, 4), label + cv::Point(36, -12), kWhite, cv::FILLED);
  PutText(panel, "1 mm", label, red, 0.4);
}

void DrawErrorBars(cv::Mat& panel, const std::vector<ExperimentPlotRun>& runs, size_t count,
                   const Axis& axis, const cv::Rect& area) {
  const double group = static_cast<double>(area.width) / std::max<size_t>(count, 1);
  const double bar = 0.8 * group / std::max<size_t>(runs.size(), 1);
  for (size_t t = 0; t < count; ++t) {
    const double left = area.x + t * group + 0.1 * group;
    if (group >= 14.0 || (t + 1) % 5 == 0) {
      PutTextAligned(panel, std::to_string(t + 1),
                     {static_cast<int>(left + 0.4 * group), area.br().y + 16}, 0.5);
    }
    for (size_t r = 0; r < runs.size(); ++r) {
      if (runs[r].score == nullptr || t >= runs[r].score->targets.size()) continue;
      const TargetScore& score = runs[r].score->targets[t];
      if (score.samples == 0 || !std::isfinite(score.tip_error_mm)) continue;
      const double value = std::clamp(score.tip_error_mm, axis.low, axis.high);
      const int x0 = static_cast<int>(std::lround(left + r * bar));
      const int x1 = static_cast<int>(std::lround(left + (r + 1) * bar)) - 1;
      cv::rectangle(panel, cv::Point(x0, axis.ToPixel(value)),
                    cv::Point(std::max(x0, x1), area.br().y), RunColour(r), cv::FILLED);
    }
  }
}

cv::Mat DrawErrorPanel(const std::vector<ExperimentPlotRun>& runs, size_t count, cv::Size size) {
  cv::Mat panel(size, CV_8UC3, kWhite);
  const cv::Rect area(70, 70, size.width - 90, size.height - 120);
  const Axis axis = FitErrorAxis(runs, area);
  DrawErrorGrid(panel, axis, area);
  DrawErrorBars(panel, runs, count, axis, area);
  DrawOneMillimetreLine(panel, axis, area);
  PutText(panel, "steady-state tip error per target (mean over the window)", {10, 20}, kInk, 0.5);
  DrawLegend(panel, runs, {90, 42});
  return panel;
}

std::string TitleLine(const std::vector<ExperimentPlotRun>& runs, const SectionLengths& rest) {
  std::string title = "mean steady-state tip error (L1 = " + TickText(rest.distal) + " mm):";
  for (const ExperimentPlotRun& run : runs) {
    if (run.score == nullptr) continue;
    title += "   " + run.mode + " " + Text(run.score->mean_tip_error_mm, 2) + " mm (" +
             Text(run.score->mean_tip_error_percent, 2) + "% of L1), " +
             std::to_string(run.score->targets_within(1.0)) + "/" +
             std::to_string(run.score->targets_scored) + " within 1 mm";
  }
  return title;
}

}  // namespace

cv::Mat DrawExperimentPlot(const std::vector<ExperimentTarget>& targets,
                           const std::vector<ExperimentPlotRun>& runs, const SectionLengths& rest) {
  std::vector<Vec3> target_tips;
  target_tips.reserve(targets.size());
  for (const ExperimentTarget& target : targets) {
    target_tips.push_back(BaseFromTip(target.q, rest).translation());
  }
  const cv::Size panel_size(kWidth / 2, kHeight - kTitleHeight);
  cv::Mat panels;
  cv::hconcat(DrawTipPanel(target_tips, runs, panel_size),
              DrawErrorPanel(runs, targets.size(), panel_size), panels);
  cv::Mat plot(kHeight, kWidth, CV_8UC3, kWhite);
  panels.copyTo(plot(cv::Rect(0, kTitleHeight, kWidth, kHeight - kTitleHeight)));
  PutTextWithin(plot, TitleLine(runs, rest), {10, 26}, kWidth - 20, 0.55);
  return plot;
}

}  // namespace shapesense
