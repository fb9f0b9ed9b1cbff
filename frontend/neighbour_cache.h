#ifndef DALA_FRONTEND_NEIGHBOUR_CACHE_H_
#define DALA_FRONTEND_NEIGHBOUR_CACHE_H_

// The k nearest other points of every interest point of an image (pixels, nearest first, ties
// by index), which the matcher's local geometric constraints use. They depend only on the
// image's points, and one image takes part in several matches (stereo as the current frame,
// temporal as the previous one, keyframe re-acquisition while it is the keyframe), so they are
// computed once per image and k and kept with the image (DetectedImage::neighbour_cache, shared
// by its copies). An entry is reused only for exactly the points it was computed from: a copy
// whose points were edited gets its own lists.

#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <vector>

namespace dala {

using NeighbourLists = std::vector<std::vector<int>>;

struct NeighbourCache {
  std::mutex mutex;
  std::vector<Eigen::Vector2d> points;  // What `lists` were computed from.
  int k = 0;
  std::shared_ptr<const NeighbourLists> lists;
};

// The k nearest neighbours of every point of `points`, from `cache` when it holds them for these
// points and k, else computed (SpatialGrid::Nearest) and stored in `cache`. Thread-safe.
std::shared_ptr<const NeighbourLists> CachedNearestNeighbours(
    const std::vector<Eigen::Vector2d>& points, int k, NeighbourCache* cache);

}  // namespace dala

#endif  // DALA_FRONTEND_NEIGHBOUR_CACHE_H_
