// RansacOrder (core/ransac_order.h), and the OpenCV behaviour it rests on: OpenCV's RANSAC does
// not read cv::theRNG(), its draws follow the order of the correspondences.

#include "core/ransac_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <random>

namespace dala {
namespace {

TEST(RansacOrder, SeedZeroKeepsTheOrder) {
  std::vector<int> identity(57);
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(RansacOrder(57, 0), identity);
  EXPECT_TRUE(RansacOrder(0, 3).empty());
}

TEST(RansacOrder, OtherSeedsShuffleRepeatably) {
  const std::vector<int> a = RansacOrder(200, 1), b = RansacOrder(200, 2);
  EXPECT_EQ(a, RansacOrder(200, 1));
  EXPECT_NE(a, b);
  std::vector<int> sorted = a;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> identity(200);
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(sorted, identity);  // A permutation.
  EXPECT_NE(a, identity);
  const std::vector<char> letters = {'a', 'b', 'c', 'd'};
  const std::vector<int> order = {2, 0, 3, 1};
  EXPECT_EQ(Reordered(letters, order), (std::vector<char>{'c', 'a', 'd', 'b'}));
  // A mask over the reordered letters (c and d kept) back in the letters' order.
  const cv::Mat mask = (cv::Mat_<uchar>(4, 1) << 1, 0, 1, 0);
  EXPECT_EQ(MaskInGivenOrder(mask, order), (std::vector<bool>{false, false, true, true}));
  EXPECT_EQ(MaskInGivenOrder(cv::Mat(), order), std::vector<bool>(4, false));
}

// Point pairs of a homography, two thirds of them moved at random: with a few RANSAC iterations
// the model depends on the samples drawn.
void HardHomographyPairs(std::vector<cv::Point2f>* a, std::vector<cv::Point2f>* b) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.f, 500.f), off(-40.f, 40.f);
  for (int i = 0; i < 150; ++i) {
    const cv::Point2f p(u(rng), u(rng));
    cv::Point2f q(1.1f * p.x + 0.05f * p.y + 7.f, -0.03f * p.x + 0.95f * p.y - 4.f);
    if (i % 3 != 0) q += cv::Point2f(off(rng), off(rng));
    a->push_back(p);
    b->push_back(q);
  }
}

cv::Mat FewIterationHomography(const std::vector<cv::Point2f>& a,
                               const std::vector<cv::Point2f>& b) {
  cv::Mat mask;
  return cv::findHomography(a, b, cv::RANSAC, 2.0, mask, /*maxIters=*/5, /*confidence=*/0.5);
}

TEST(RansacOrder, OpenCvRansacIgnoresTheRngAndFollowsTheOrder) {
  std::vector<cv::Point2f> a, b;
  HardHomographyPairs(&a, &b);
  // cv::theRNG() does not reach the draws (were it to, core/ransac_order.h would need revisiting).
  cv::theRNG().state = 1;
  const cv::Mat h1 = FewIterationHomography(a, b);
  cv::theRNG().state = 12345;
  const cv::Mat h2 = FewIterationHomography(a, b);
  ASSERT_FALSE(h1.empty());
  EXPECT_EQ(cv::norm(h1, h2, cv::NORM_INF), 0.0);
  // The order does.
  int different = 0;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const std::vector<int> order = RansacOrder(a.size(), seed);
    const cv::Mat h = FewIterationHomography(Reordered(a, order), Reordered(b, order));
    different += !h.empty() && cv::norm(h, h1, cv::NORM_INF) > 1e-6;
  }
  EXPECT_GE(different, 3);
}

}  // namespace
}  // namespace dala
