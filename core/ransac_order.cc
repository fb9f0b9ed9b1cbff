#include "core/ransac_order.h"

#include <algorithm>
#include <numeric>
#include <random>

namespace dala {

std::vector<int> RansacOrder(size_t n, uint64_t seed) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  if (seed != 0) {
    std::mt19937_64 rng(seed);
    std::shuffle(order.begin(), order.end(), rng);
  }
  return order;
}

std::vector<bool> MaskInGivenOrder(const cv::Mat& mask, const std::vector<int>& order) {
  std::vector<bool> flags(order.size(), false);
  if (mask.empty()) return flags;
  for (size_t k = 0; k < order.size(); ++k) {
    flags[static_cast<size_t>(order[k])] = mask.at<uchar>(static_cast<int>(k)) != 0;
  }
  return flags;
}

}  // namespace dala
