#include "backend/mono/loop_sim3.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

struct Pairs {
  std::vector<Eigen::Vector3d> cur, old;
};

// Points 3-20 m in front of a camera at the origin of world_cur, seen again in world_old =
// S_true * world_cur, with noise of 1 % of the distance and a fraction of wrong matches.
Pairs MakePairs(const Sim3& S_true, int n, double outlier_fraction, std::mt19937& rng) {
  std::uniform_real_distribution<double> xy(-8.0, 8.0), z(3.0, 20.0), u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  Pairs p;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d q(xy(rng), xy(rng) * 0.3, z(rng));
    Eigen::Vector3d q_old = S_true * q;
    if (u(rng) < outlier_fraction) {
      q_old = S_true * Eigen::Vector3d(xy(rng), xy(rng), z(rng));
    } else {
      q_old += 0.01 * S_true.scale * q.norm() * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    }
    p.cur.push_back(q);
    p.old.push_back(q_old);
  }
  return p;
}

Sim3 TrueSim3() {
  Sim3 S;
  S.T = MakePose(Eigen::Matrix3d(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())),
                 Eigen::Vector3d(5.0, -0.5, 12.0));
  S.scale = 1.35;  // The current neighbourhood's unit is 35 % too small.
  return S;
}

TEST(LoopSim3Test, RecoversTheSimilarityDespiteWrongMatches) {
  std::mt19937 rng(7);
  const Sim3 S_true = TrueSim3();
  const Pairs p = MakePairs(S_true, 80, 0.3, rng);
  const std::optional<LoopSim3> r =
      EstimateLoopSim3(p.cur, p.old, Eigen::Vector3d::Zero(), LoopSim3Options());
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->S_old_cur.scale, S_true.scale, 0.02);
  EXPECT_POSE_NEAR(r->S_old_cur.T, S_true.T, 0.1);
  EXPECT_GE(r->inliers, 45);  // ~56 true pairs, a few beyond 5 % noise.
  EXPECT_LE(r->inliers, 64);
}

TEST(LoopSim3Test, RefusesPairsThatAgreeOnNothing) {
  std::mt19937 rng(8);
  const Pairs p = MakePairs(TrueSim3(), 80, 1.0, rng);
  EXPECT_FALSE(EstimateLoopSim3(p.cur, p.old, Eigen::Vector3d::Zero(), LoopSim3Options()));
}

TEST(LoopSim3Test, Deterministic) {
  std::mt19937 rng(9);
  const Pairs p = MakePairs(TrueSim3(), 60, 0.4, rng);
  const auto a = EstimateLoopSim3(p.cur, p.old, Eigen::Vector3d::Zero(), LoopSim3Options());
  const auto b = EstimateLoopSim3(p.cur, p.old, Eigen::Vector3d::Zero(), LoopSim3Options());
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->inlier, b->inlier);
  EXPECT_EQ(a->S_old_cur.T.matrix(), b->S_old_cur.T.matrix());
}

}  // namespace
}  // namespace dala
