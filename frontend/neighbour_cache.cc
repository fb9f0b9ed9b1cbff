#include "frontend/neighbour_cache.h"

#include <glog/logging.h>

#include "frontend/spatial_grid.h"

namespace dala {

std::shared_ptr<const NeighbourLists> CachedNearestNeighbours(
    const std::vector<Eigen::Vector2d>& points, int k, NeighbourCache* cache) {
  CHECK(cache != nullptr);
  std::lock_guard<std::mutex> lock(cache->mutex);
  if (cache->lists && cache->k == k && cache->points == points) return cache->lists;
  // The grid's cell size only changes the search cost, not the result.
  const SpatialGrid grid(points, 24.0);
  auto lists = std::make_shared<NeighbourLists>(points.size());
  for (size_t i = 0; i < points.size(); ++i) (*lists)[i] = grid.Nearest(static_cast<int>(i), k);
  cache->points = points;
  cache->k = k;
  cache->lists = std::move(lists);
  return cache->lists;
}

}  // namespace dala
