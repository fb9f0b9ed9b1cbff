#include "core/eval/association.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/core/eval/eval_test_util.h"

namespace dala {
namespace {

Trajectory Stamps(const std::vector<int64_t>& t_ns) {
  Trajectory t;
  for (int64_t s : t_ns) t.Add(s, Pose::Identity());
  return t;
}

constexpr int64_t kMs = 1000000;

TEST(Association, JitteredStampsMatchTheNearest) {
  // Ground truth at 100 Hz, estimate at ~30 Hz with up to +-3 ms of jitter.
  std::vector<int64_t> gt_t, est_t;
  for (int i = 0; i < 1000; ++i) gt_t.push_back(5000 * kMs + i * 10 * kMs);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int64_t> jitter(-3 * kMs, 3 * kMs);
  for (int i = 0; i < 300; ++i) est_t.push_back(5000 * kMs + i * 33 * kMs + jitter(rng));
  const Trajectory gt = Stamps(gt_t), est = Stamps(est_t);
  const auto matches = AssociateByTime(gt, est, 10 * kMs);
  EXPECT_EQ(matches.size(), est.size());  // Every estimate stamp has a gt stamp within 5 ms.
  for (const PoseMatch& m : matches) {
    const int64_t dt = std::llabs(gt_t[m.gt] - est_t[m.est]);
    EXPECT_LE(dt, 5 * kMs);  // The nearest 100 Hz stamp is at most 5 ms away.
    // Nearest: no other gt stamp is closer.
    if (m.gt > 0) {
      EXPECT_GE(std::llabs(gt_t[m.gt - 1] - est_t[m.est]), dt);
    }
    if (m.gt + 1 < gt_t.size()) {
      EXPECT_GE(std::llabs(gt_t[m.gt + 1] - est_t[m.est]), dt);
    }
  }
  for (size_t k = 1; k < matches.size(); ++k) EXPECT_LT(matches[k - 1].est, matches[k].est);
}

TEST(Association, MissingPosesAndMaxDiff) {
  // Ground truth has a gap between 1.0 and 2.0 s.
  const Trajectory gt = Stamps({900 * kMs, 1000 * kMs, 2000 * kMs, 2100 * kMs});
  const Trajectory est = Stamps({905 * kMs, 1500 * kMs, 1995 * kMs, 2100 * kMs});
  auto m = AssociateByTime(gt, est, 10 * kMs);
  ASSERT_EQ(m.size(), 3u);  // 1.5 s has no ground truth within 10 ms.
  EXPECT_EQ(m[0].gt, 0u);
  EXPECT_EQ(m[1].est, 2u);
  EXPECT_EQ(m[1].gt, 2u);
  // max_diff 0: exact stamps only; a boundary difference equal to max_diff is accepted.
  EXPECT_EQ(AssociateByTime(gt, est, 0).size(), 1u);
  EXPECT_EQ(AssociateByTime(gt, est, 5 * kMs).size(), 3u);
  EXPECT_EQ(AssociateByTime(gt, est, 4 * kMs).size(), 1u);
}

TEST(Association, EachPoseIsUsedOnceClosestFirst) {
  // Two estimate stamps compete for one ground truth stamp: the closer one wins, the other
  // stays unmatched although it is within max_diff (TUM associate.py semantics).
  const Trajectory gt = Stamps({1003 * kMs});
  const Trajectory est = Stamps({1000 * kMs, 1004 * kMs});
  const auto m = AssociateByTime(gt, est, 10 * kMs);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].est, 1u);
  // And the symmetric case: two gt stamps for one estimate stamp.
  const auto m2 = AssociateByTime(Stamps({990 * kMs, 1002 * kMs}), Stamps({1000 * kMs}), 10 * kMs);
  ASSERT_EQ(m2.size(), 1u);
  EXPECT_EQ(m2[0].gt, 1u);
}

TEST(PairTrajectories, KittiPairsByIndexAndNeedsEqualLengths) {
  Trajectory a = testing::HelixTrajectory(10);
  a.has_timestamps = false;
  Trajectory b = a;
  PairedPoses pairs;
  std::string why;
  ASSERT_TRUE(PairTrajectories(a, b, 0.01, &pairs, &why));
  EXPECT_TRUE(pairs.by_index);
  EXPECT_EQ(pairs.size(), 10u);
  b.poses.pop_back();
  EXPECT_FALSE(PairTrajectories(a, b, 0.01, &pairs, &why));
  EXPECT_NE(why.find("10 poses"), std::string::npos) << why;
  EXPECT_NE(why.find("--times"), std::string::npos) << why;
  // One with stamps, one without: no meaningful pairing.
  b = testing::HelixTrajectory(10);
  EXPECT_FALSE(PairTrajectories(a, b, 0.01, &pairs, &why));
  EXPECT_NE(why.find("no timestamps"), std::string::npos) << why;
}

TEST(PairTrajectories, NoPairsSaysMaxDiffAndTimeRanges) {
  const Trajectory gt = testing::HelixTrajectory(10, 1000000000LL);
  const Trajectory est = testing::HelixTrajectory(10, 50000000000LL);
  PairedPoses pairs;
  std::string why;
  EXPECT_FALSE(PairTrajectories(gt, est, 0.02, &pairs, &why));
  EXPECT_NE(why.find("0.02"), std::string::npos) << why;
  EXPECT_NE(why.find("[1.000000, 1.900000] s"), std::string::npos) << why;
  EXPECT_NE(why.find("[50.000000, 50.900000] s"), std::string::npos) << why;
  Trajectory empty;
  EXPECT_FALSE(PairTrajectories(gt, empty, 0.02, &pairs, &why));
}

}  // namespace
}  // namespace dala
