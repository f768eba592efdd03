#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/carving/voxel_grid.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {

// Pictures for people: what each camera saw with the silhouette outline (cyan),
// tape pixels (magenta), the measured centreline (yellow), markers (red
// circles) and, when given, the true centreline (thin green).
cv::Mat DrawCameraOverlay(const cv::Mat& image, const Silhouette& silhouette, const Camera& camera,
                          const ShapeEstimate& shape, const Polyline* truth = nullptr);

// Three orthogonal projections (x-y, x-z, y-z) of the voxels (grey, tape in
// red) with the measured centreline (yellow) and the truth (green), side by
// side, with axis labels and a 10 mm scale bar.
cv::Mat DrawOrthogonalViews(const VoxelCloud& cloud, const ShapeEstimate& shape,
                            const Polyline* truth = nullptr, int view_size_px = 360);

// Tiles images of equal type into a grid, `columns` wide.
cv::Mat TileImages(const std::vector<cv::Mat>& images, int columns);

}  // namespace shapesense
