#include "libs/sim/ray_table.h"

#include <algorithm>
#include <cmath>

namespace shapesense {
namespace {

// Spacing of the grid where the inverse distortion is solved exactly, px.
constexpr int kGridStep = 16;

// Undistorted normalised coordinates on a grid covering the image (one node
// beyond the last pixel so every pixel has a full cell).
struct UndistortGrid {
  int columns = 0;
  int rows = 0;
  std::vector<Vec2> nodes;

  const Vec2& at(int i, int j) const { return nodes[static_cast<size_t>(j) * columns + i]; }
};

UndistortGrid SolveGrid(const Camera& camera) {
  UndistortGrid grid;
  grid.columns = (camera.width - 1) / kGridStep + 2;
  grid.rows = (camera.height - 1) / kGridStep + 2;
  grid.nodes.reserve(static_cast<size_t>(grid.columns) * grid.rows);
  for (int j = 0; j < grid.rows; ++j) {
    for (int i = 0; i < grid.columns; ++i) {
      grid.nodes.push_back(camera.UnscaleAndUndistort(Vec2(i * kGridStep, j * kGridStep)));
    }
  }
  return grid;
}

// The grid spans the image from its first pixel centre to beyond its last;
// a margin of a few pixels covers the first half pixel.
RayTable::Bounds GridBounds(const Camera& camera, const UndistortGrid& grid) {
  RayTable::Bounds bounds{1e9, 1e9, -1e9, -1e9};
  for (const Vec2& n : grid.nodes) {
    bounds = {std::min(bounds.x0, n.x()), std::min(bounds.y0, n.y()), std::max(bounds.x1, n.x()),
              std::max(bounds.y1, n.y())};
  }
  const double margin_x = 4.0 / camera.camera_matrix(0, 0);
  const double margin_y = 4.0 / camera.camera_matrix(1, 1);
  return {bounds.x0 - margin_x, bounds.y0 - margin_y, bounds.x1 + margin_x, bounds.y1 + margin_y};
}

// One row of pixels inside one grid cell: the undistorted coordinates vary
// linearly along it, between the cell's left and right edges at this height.
struct CellRow {
  Vec2 left, right;  // at the row's height, on the cell's left and right edges
  Vec2 down_left;    // d normalised / d v on the left edge
  Vec2 down_right;   // ... and on the right edge
};

CellRow MakeCellRow(const UndistortGrid& grid, int i, int j, double fv) {
  const Vec2& n00 = grid.at(i, j);
  const Vec2& n10 = grid.at(i + 1, j);
  const Vec2& n01 = grid.at(i, j + 1);
  const Vec2& n11 = grid.at(i + 1, j + 1);
  return {(1 - fv) * n00 + fv * n01, (1 - fv) * n10 + fv * n11, (n01 - n00) / kGridStep,
          (n11 - n10) / kGridStep};
}

// The pixel's undistorted coordinates: bilinear start, then one Newton step
// on the forward model with the interpolant's Jacobian.
Vec2 UndistortPixel(const Camera& camera, const CellRow& cell, double fu, const Vec2& pixel) {
  const Vec2 along_u = (cell.right - cell.left) / kGridStep;
  const Vec2 along_v = (1 - fu) * cell.down_left + fu * cell.down_right;
  const Vec2 guess = cell.left + fu * (cell.right - cell.left);
  const Vec2 residual = pixel - camera.DistortAndScale(guess);
  return guess + residual.x() * along_u + residual.y() * along_v;
}

// Angle a pixel subtends at normalised coordinates n where the Jacobian of
// normalised by pixel coordinates has columns `along_u`, `along_v`: the square
// root of its solid angle, normalised-plane area × cos³ of the ray's angle.
double PixelAngle(const Vec2& n, const Vec2& along_u, const Vec2& along_v) {
  const double area = std::abs(along_u.x() * along_v.y() - along_u.y() * along_v.x());
  return std::sqrt(area * std::pow(n.squaredNorm() + 1.0, -1.5));
}

void FillRow(const Camera& camera, const UndistortGrid& grid, int v, RayTable::Ray* row) {
  const int j = v / kGridStep;
  const double fv = static_cast<double>(v - j * kGridStep) / kGridStep;
  for (int i = 0; i * kGridStep < camera.width; ++i) {
    const CellRow cell = MakeCellRow(grid, i, j, fv);
    // The pixel angle varies slowly: solved at the cell's edges, interpolated between.
    const Vec2 along_u = (cell.right - cell.left) / kGridStep;
    const double angle_left = PixelAngle(cell.left, along_u, cell.down_left);
    const double angle_right = PixelAngle(cell.right, along_u, cell.down_right);
    const int end = std::min(camera.width, (i + 1) * kGridStep);
    for (int u = i * kGridStep; u < end; ++u) {
      const double fu = static_cast<double>(u - i * kGridStep) / kGridStep;
      const Vec2 n = UndistortPixel(camera, cell, fu, Vec2(u, v));
      const double inverse_norm = 1.0 / std::sqrt(n.squaredNorm() + 1.0);
      row[u] = {static_cast<float>(n.x() * inverse_norm), static_cast<float>(n.y() * inverse_norm),
                static_cast<float>(inverse_norm),
                static_cast<float>(angle_left + fu * (angle_right - angle_left))};
    }
  }
}

}  // namespace

RayTable BuildRayTable(const Camera& camera) {
  RayTable table;
  table.width = camera.width;
  table.height = camera.height;
  table.rays.resize(static_cast<size_t>(camera.width) * camera.height);
  const UndistortGrid grid = SolveGrid(camera);
  table.image_bounds = GridBounds(camera, grid);
  for (int v = 0; v < camera.height; ++v) {
    FillRow(camera, grid, v, &table.rays[static_cast<size_t>(v) * camera.width]);
  }
  return table;
}

}  // namespace shapesense
