#include "frontend/spatial_grid.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace dala {

SpatialGrid::SpatialGrid(const std::vector<Eigen::Vector2d>& points, double cell_size)
    : points_(points), cell_size_(cell_size) {
  CHECK_GT(cell_size, 0.0) << "SpatialGrid cell size must be positive";
  if (points_.empty()) {
    cells_.resize(1);
    return;
  }
  double max_x = points_[0].x(), max_y = points_[0].y();
  min_x_ = max_x;
  min_y_ = max_y;
  for (const auto& p : points_) {
    min_x_ = std::min(min_x_, p.x());
    min_y_ = std::min(min_y_, p.y());
    max_x = std::max(max_x, p.x());
    max_y = std::max(max_y, p.y());
  }
  nx_ = std::min(4096, static_cast<int>((max_x - min_x_) / cell_size_) + 1);
  ny_ = std::min(4096, static_cast<int>((max_y - min_y_) / cell_size_) + 1);
  cells_.resize(static_cast<size_t>(nx_) * ny_);
  for (size_t i = 0; i < points_.size(); ++i) {
    cells_[static_cast<size_t>(CellY(points_[i].y())) * nx_ + CellX(points_[i].x())].push_back(
        static_cast<int>(i));
  }
}

int SpatialGrid::CellX(double x) const {
  return std::clamp(static_cast<int>(std::floor((x - min_x_) / cell_size_)), 0, nx_ - 1);
}
int SpatialGrid::CellY(double y) const {
  return std::clamp(static_cast<int>(std::floor((y - min_y_) / cell_size_)), 0, ny_ - 1);
}

std::vector<int> SpatialGrid::InRadius(const Eigen::Vector2d& center, double radius) const {
  std::vector<int> out;
  if (points_.empty()) return out;
  const int x0 = CellX(center.x() - radius), x1 = CellX(center.x() + radius);
  const int y0 = CellY(center.y() - radius), y1 = CellY(center.y() + radius);
  const double r2 = radius * radius;
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      for (int i : cells_[static_cast<size_t>(cy) * nx_ + cx]) {
        if ((points_[i] - center).squaredNorm() <= r2) out.push_back(i);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> SpatialGrid::Nearest(int index, int k) const {
  CHECK(index >= 0 && index < static_cast<int>(points_.size())) << "SpatialGrid: bad index";
  const Eigen::Vector2d& c = points_[index];
  const int cx = CellX(c.x()), cy = CellY(c.y());
  std::vector<std::pair<double, int>> found;
  // Grow square rings of cells; once k points are found, one more ring guarantees correctness
  // when the ring's inner distance exceeds the current k-th distance.
  for (int ring = 0; ring <= std::max(nx_, ny_); ++ring) {
    for (int y = cy - ring; y <= cy + ring; ++y) {
      if (y < 0 || y >= ny_) continue;
      for (int x = cx - ring; x <= cx + ring; ++x) {
        if (x < 0 || x >= nx_) continue;
        if (std::max(std::abs(x - cx), std::abs(y - cy)) != ring) continue;
        for (int i : cells_[static_cast<size_t>(y) * nx_ + x]) {
          if (i != index) found.emplace_back((points_[i] - c).squaredNorm(), i);
        }
      }
    }
    if (static_cast<int>(found.size()) >= k) {
      std::nth_element(found.begin(), found.begin() + (k - 1), found.end());
      const double kth = std::sqrt(found[k - 1].first);
      if (kth <= ring * cell_size_) break;  // Every unvisited point is farther than ring*cell.
    }
  }
  std::sort(found.begin(), found.end());
  if (static_cast<int>(found.size()) > k) found.resize(k);
  std::vector<int> out;
  out.reserve(found.size());
  for (const auto& f : found) out.push_back(f.second);
  return out;
}

}  // namespace dala
