#ifndef DALA_FRONTEND_SPATIAL_GRID_H_
#define DALA_FRONTEND_SPATIAL_GRID_H_

// A uniform bucket grid over 2D points for radius and k-nearest-neighbour queries in pixel
// coordinates. Points outside the grid's extent are clamped into the border cells, so every point
// is findable. Queries return indices in increasing index order (radius) or increasing distance
// (kNN, ties by index): results are deterministic.

#include <Eigen/Core>
#include <vector>

namespace dala {

class SpatialGrid {
 public:
  // `cell_size` in pixels (> 0). The points are copied.
  SpatialGrid(const std::vector<Eigen::Vector2d>& points, double cell_size);

  // Indices of the points within `radius` of `center` (inclusive), sorted by index.
  std::vector<int> InRadius(const Eigen::Vector2d& center, double radius) const;

  // The k nearest points to points()[index], excluding itself, nearest first.
  std::vector<int> Nearest(int index, int k) const;

  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  int CellX(double x) const;
  int CellY(double y) const;

  std::vector<Eigen::Vector2d> points_;
  double cell_size_;
  double min_x_ = 0.0, min_y_ = 0.0;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<int>> cells_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_SPATIAL_GRID_H_
