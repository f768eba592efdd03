#include "libs/calibration/synthetic_board.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace shapesense {
namespace {

// Normalised undistorted coordinates of every pixel corner: (width + 1) x
// (height + 1) entries, corner (i, j) at pixel position (i - 0.5, j - 0.5).
// Inside a pixel the map is bilinear to ~1e-4 px for real lenses.
std::vector<Vec2> PixelCornerRays(const Camera& camera) {
  std::vector<Vec2> rays;
  rays.reserve(static_cast<size_t>(camera.width + 1) * static_cast<size_t>(camera.height + 1));
  for (int j = 0; j <= camera.height; ++j) {
    for (int i = 0; i <= camera.width; ++i) {
      rays.push_back(camera.UnscaleAndUndistort(Vec2(i - 0.5, j - 0.5)));
    }
  }
  return rays;
}

// Traces rays through one camera into the board's plane.
class BoardTracer {
 public:
  BoardTracer(const CalibrationBoard& board, const Pose3& cam_from_board,
              const BoardRenderOptions& options)
      : board_(board), options_(options) {
    const Pose3 board_from_cam = cam_from_board.inverse();
    rotation_ = board_from_cam.linear();
    origin_ = board_from_cam.translation();
  }

  // Grey level seen along the ray through normalised coordinates n.
  double Trace(const Vec2& n) const {
    const Vec3 direction = rotation_ * Vec3(n.x(), n.y(), 1.0);
    const double t = -origin_.z() / direction.z();
    if (!(t > 0.0)) return options_.background;
    const Vec3 hit = origin_ + t * direction;
    const std::optional<double> reflectance = board_.Reflectance(hit.x(), hit.y());
    if (!reflectance) return options_.background;
    return options_.dark + (options_.light - options_.dark) * *reflectance;
  }

 private:
  const CalibrationBoard& board_;
  const BoardRenderOptions& options_;
  Mat3 rotation_;
  Vec3 origin_;
};

// Mean grey level over the pixel whose corners' rays are c00 .. c11.
double SupersamplePixel(const BoardTracer& tracer, const Vec2& c00, const Vec2& c10,
                        const Vec2& c01, const Vec2& c11, int samples) {
  double sum = 0.0;
  for (int b = 0; b < samples; ++b) {
    const double v = (b + 0.5) / samples;
    const Vec2 left = c00 + v * (c01 - c00);
    const Vec2 right = c10 + v * (c11 - c10);
    for (int a = 0; a < samples; ++a) {
      sum += tracer.Trace(left + ((a + 0.5) / samples) * (right - left));
    }
  }
  return sum / (samples * samples);
}

}  // namespace

std::string BoardRenderOptions::Validate() const {
  std::ostringstream error;
  const auto grey = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 255.0; };
  if (supersampling < 1 || supersampling > 16) {
    error << "supersampling: expected 1-16, got " << supersampling;
  } else if (!grey(dark) || !grey(light) || !grey(background)) {
    error << "dark, light, background: expected grey levels 0-255, got " << dark << ", " << light
          << ", " << background;
  } else if (!std::isfinite(noise_sigma) || noise_sigma < 0.0) {
    error << "noise_sigma: expected a number >= 0, got " << noise_sigma;
  }
  return error.str();
}

BoardViewRenderer::BoardViewRenderer(const Camera& camera)
    : width_(camera.width), height_(camera.height), corner_rays_(PixelCornerRays(camera)) {}

cv::Mat BoardViewRenderer::Render(const CalibrationBoard& board, const Pose3& cam_from_board,
                                  const BoardRenderOptions& options) const {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("BoardViewRenderer: " + error);
  }
  const BoardTracer tracer(board, cam_from_board, options);
  std::vector<double> corner_grey(corner_rays_.size());
  for (size_t i = 0; i < corner_rays_.size(); ++i) corner_grey[i] = tracer.Trace(corner_rays_[i]);
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> noise(0.0, options.noise_sigma);
  const size_t w = static_cast<size_t>(width_) + 1;
  cv::Mat image(height_, width_, CV_8UC1);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * w + static_cast<size_t>(x);
      const double g = corner_grey[i];
      const bool uniform =
          corner_grey[i + 1] == g && corner_grey[i + w] == g && corner_grey[i + w + 1] == g;
      double grey = uniform ? g
                            : SupersamplePixel(tracer, corner_rays_[i], corner_rays_[i + 1],
                                               corner_rays_[i + w], corner_rays_[i + w + 1],
                                               options.supersampling);
      if (options.noise_sigma > 0.0) grey += noise(rng);
      image.at<uint8_t>(y, x) = static_cast<uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
    }
  }
  return image;
}

cv::Mat RenderBoardView(const Camera& camera, const CalibrationBoard& board,
                        const Pose3& cam_from_board, const BoardRenderOptions& options) {
  return BoardViewRenderer(camera).Render(board, cam_from_board, options);
}

}  // namespace shapesense
