// SeededPnpRansac (core/cv_pose.h): the pose of a camera from exact pixels of known points,
// with outliers among them, at any seed; too few points give no pose.

#include "core/cv_pose.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace dala {
namespace {

TEST(SeededPnpRansac, RecoversTheCameraPoseAndCountsTheOutliersOut) {
  Eigen::Matrix3d K;
  K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  const Pose T_c_o = MakePose(
      Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()).toRotationMatrix(),
      Eigen::Vector3d(0.4, -0.1, 1.5));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> xy(-3, 3), z(4, 20), px(0, 640);
  std::vector<Eigen::Vector3d> p_o;
  std::vector<Eigen::Vector2d> uv;
  for (int i = 0; i < 80; ++i) {
    const Eigen::Vector3d p(xy(rng), xy(rng), z(rng));
    const Eigen::Vector3d p_c = T_c_o * p;
    p_o.push_back(p);
    // Every 5th pixel is elsewhere in the image: 16 outliers.
    uv.push_back(i % 5 == 0 ? Eigen::Vector2d(px(rng), px(rng) * 0.75)
                            : Eigen::Vector2d((K * p_c).hnormalized()));
  }
  for (const uint64_t seed : {0, 7}) {
    const PnpRansacResult r = SeededPnpRansac(p_o, uv, K, 2.0, seed);
    ASSERT_TRUE(r.found) << "seed " << seed;
    EXPECT_EQ(r.inliers, 64) << "seed " << seed;
    EXPECT_LT((r.T_c_o.translation() - T_c_o.translation()).norm(), 1e-6) << "seed " << seed;
    EXPECT_LT((r.T_c_o.linear() - T_c_o.linear()).norm(), 1e-6) << "seed " << seed;
  }
  const PnpRansacResult none = SeededPnpRansac({p_o[1], p_o[2]}, {uv[1], uv[2]}, K, 2.0, 0);
  EXPECT_FALSE(none.found);
  EXPECT_TRUE(none.T_c_o.isApprox(Pose::Identity()));
}

}  // namespace
}  // namespace dala
