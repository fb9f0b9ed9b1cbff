#ifndef DALA_CORE_RANSAC_ORDER_H_
#define DALA_CORE_RANSAC_ORDER_H_

// The order in which correspondences are handed to OpenCV's RANSAC.
//
// OpenCV's robust estimators (cv::findEssentialMat, cv::findHomography, cv::findFundamentalMat,
// cv::solvePnPRansac; RANSAC and USAC, OpenCV 4.x) seed their own generator on every call and do
// not read cv::theRNG(): the same correspondences in the same order always give the same
// samples, whatever cv::theRNG() holds. Their draws are changed by the order alone, so a seed for
// them is a permutation: RansacOrder(n, seed) is the identity for seed 0 (the correspondences as
// given: OpenCV's own draws) and std::shuffle with std::mt19937_64(seed) otherwise. The same n and
// seed give the same order with the same standard library (the generator's sequence is fixed by
// the standard, std::shuffle's use of it by the library).
//
// Usage, for correspondences a[i] <-> b[i]:
//   const std::vector<int> order = RansacOrder(a.size(), seed);
//   cv::findHomography(Reordered(a, order), Reordered(b, order), cv::RANSAC, th, mask);
//   std::vector<bool> inlier = MaskInGivenOrder(mask, order);  // mask is in the reordered one.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace dala {

std::vector<int> RansacOrder(size_t n, uint64_t seed);

// A RANSAC inlier mask over the reordered correspondences (its k-th entry is correspondence
// order[k]) as flags in the correspondences' own order; all false when the mask is empty (no
// model). mask: CV_8U with order.size() entries, as OpenCV's estimators write it.
std::vector<bool> MaskInGivenOrder(const cv::Mat& mask, const std::vector<int>& order);

// out[k] = v[order[k]].
template <typename T>
std::vector<T> Reordered(const std::vector<T>& v, const std::vector<int>& order) {
  std::vector<T> out;
  out.reserve(order.size());
  for (const int i : order) out.push_back(v[static_cast<size_t>(i)]);
  return out;
}

}  // namespace dala

#endif  // DALA_CORE_RANSAC_ORDER_H_
