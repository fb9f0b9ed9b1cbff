#include "backend/ba/pose_graph.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

// A loop of 40 keyframes on a circle; odometry edges with noise and a systematic yaw bias
// (drift), one correct loop edge from the last keyframe back to the first.
TEST(PoseGraphTest, LoopClosureRemovesMostOfTheDrift) {
  const int n = 40;
  std::vector<Pose> gt;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    gt.push_back(
        MakePose(Eigen::Matrix3d(Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY())),
                 Eigen::Vector3d(10.0 * std::sin(a), 0.2 * std::sin(3 * a), 10.0 * std::cos(a))));
  }
  std::mt19937 rng(4);
  std::normal_distribution<double> nd(0.0, 1.0);
  const double sigma_rot = 0.002, sigma_trans = 0.01;
  Matrix6d info = Matrix6d::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_rot * sigma_rot)),
      Eigen::Vector3d::Constant(1.0 / (sigma_trans * sigma_trans));
  std::vector<PoseGraphEdge> edges;
  std::map<KeyframeId, Pose> initial;
  initial[KeyframeId(0)] = gt[0];
  for (int i = 1; i < n; ++i) {
    Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = nd(rng) * (k < 3 ? sigma_rot : sigma_trans);
    xi[1] += 0.01;  // yaw bias: drift.
    const Pose meas = gt[i - 1].inverse() * gt[i] * ExpSE3(xi);
    edges.push_back({KeyframeId(i - 1), KeyframeId(i), meas, info, false});
    initial[KeyframeId(i)] = initial[KeyframeId(i - 1)] * meas;
  }
  edges.push_back({KeyframeId(n - 1), KeyframeId(0), gt[n - 1].inverse() * gt[0], info, true});

  auto error = [&](const std::map<KeyframeId, Pose>& poses) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      sum += (poses.at(KeyframeId(i)).translation() - gt[i].translation()).squaredNorm();
    }
    return std::sqrt(sum / n);
  };
  PoseGraphSummary summary;
  const auto corrected = OptimizePoseGraph(initial, edges, PoseGraphOptions(), &summary);
  ASSERT_TRUE(summary.usable);
  const double before = error(initial), after = error(corrected);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(after, 0.2 * before) << "before " << before << " after " << after;
  EXPECT_TRUE(corrected.at(KeyframeId(0)).isApprox(gt[0]));  // gauge held.
  EXPECT_LT(summary.final_cost, summary.initial_cost);
}

TEST(PoseGraphTest, ConsistentEdgesAreAFixedPoint) {
  std::mt19937 rng(1);
  std::map<KeyframeId, Pose> poses;
  std::vector<PoseGraphEdge> edges;
  for (int i = 0; i < 5; ++i) poses[KeyframeId(i)] = testing::RandomPose(rng, 0.5, 3.0);
  for (int i = 1; i < 5; ++i) {
    edges.push_back({KeyframeId(i - 1), KeyframeId(i),
                     poses[KeyframeId(i - 1)].inverse() * poses[KeyframeId(i)],
                     Matrix6d::Identity(), false});
  }
  const auto out = OptimizePoseGraph(poses, edges, PoseGraphOptions());
  for (const auto& [id, T] : poses) EXPECT_POSE_NEAR(out.at(id), T, 1e-9);
}

TEST(PoseGraphDeathTest, EdgeToUnknownKeyframeDies) {
  std::map<KeyframeId, Pose> poses{{KeyframeId(0), Pose::Identity()}};
  std::vector<PoseGraphEdge> edges{
      {KeyframeId(0), KeyframeId(7), Pose::Identity(), Matrix6d::Identity(), false}};
  EXPECT_DEATH(OptimizePoseGraph(poses, edges, PoseGraphOptions()), "unknown keyframe");
}

}  // namespace
}  // namespace dala
