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

}  // namespace dala
