#include "frontend/neighbour_cache.h"

#include <gtest/gtest.h>

#include <random>
#include <thread>

#include "frontend/spatial_grid.h"

namespace dala {
namespace {

std::vector<Eigen::Vector2d> RandomPoints(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector2d> points(n);
  for (auto& p : points) p = Eigen::Vector2d(752.0 * u(rng), 480.0 * u(rng));
  return points;
}

// Brute force: the k nearest other points, nearest first, ties by index.
std::vector<int> BruteForceNearest(const std::vector<Eigen::Vector2d>& points, int index, int k) {
  std::vector<std::pair<double, int>> all;
  for (size_t j = 0; j < points.size(); ++j) {
    if (static_cast<int>(j) != index)
      all.emplace_back((points[j] - points[index]).squaredNorm(), j);
  }
  std::sort(all.begin(), all.end());
  std::vector<int> out;
  for (int i = 0; i < k && i < static_cast<int>(all.size()); ++i) out.push_back(all[i].second);
  return out;
}

TEST(NeighbourCache, ListsAreTheNearestPointsAndAreComputedOncePerPointsAndK) {
  const std::vector<Eigen::Vector2d> points = RandomPoints(600, 3);
  NeighbourCache cache;
  const auto lists = CachedNearestNeighbours(points, 12, &cache);
  ASSERT_EQ(lists->size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ((*lists)[i], BruteForceNearest(points, static_cast<int>(i), 12)) << "point " << i;
  }
  // Same points and k: the stored lists themselves.
  EXPECT_EQ(CachedNearestNeighbours(points, 12, &cache).get(), lists.get());
  // Another k: recomputed.
  const auto lists6 = CachedNearestNeighbours(points, 6, &cache);
  EXPECT_NE(lists6.get(), lists.get());
  EXPECT_EQ((*lists6)[7], BruteForceNearest(points, 7, 6));
  // One point moved (same count): recomputed, and the earlier lists are still valid to hold.
  std::vector<Eigen::Vector2d> moved = points;
  moved[42] += Eigen::Vector2d(100.0, -50.0);
  const auto lists_moved = CachedNearestNeighbours(moved, 6, &cache);
  EXPECT_NE(lists_moved.get(), lists6.get());
  for (size_t i = 0; i < moved.size(); ++i) {
    ASSERT_EQ((*lists_moved)[i], BruteForceNearest(moved, static_cast<int>(i), 6));
  }
  EXPECT_EQ(lists->size(), points.size());
}

TEST(NeighbourCache, ConcurrentUsersGetTheSameLists) {
  const std::vector<Eigen::Vector2d> points = RandomPoints(400, 4);
  NeighbourCache cache;
  std::shared_ptr<const NeighbourLists> a, b;
  std::thread t([&] { a = CachedNearestNeighbours(points, 12, &cache); });
  b = CachedNearestNeighbours(points, 12, &cache);
  t.join();
  EXPECT_EQ(a.get(), b.get());
  EXPECT_EQ((*a)[0], BruteForceNearest(points, 0, 12));
}

}  // namespace
}  // namespace dala
