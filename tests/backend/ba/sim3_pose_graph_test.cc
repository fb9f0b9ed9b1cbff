#include "backend/ba/sim3_pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

Sim3 RandomSim3(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.5, 2.0);
  Sim3 S;
  S.T = testing::RandomPose(rng, 1.0, 3.0);
  S.scale = u(rng);
  return S;
}

TEST(Sim3Test, CompositionActsLikeApplyingInTurnAndTheInverseUndoes) {
  std::mt19937 rng(3);
  const Sim3 a = RandomSim3(rng), b = RandomSim3(rng);
  const Eigen::Vector3d p(0.3, -1.2, 4.0);
  EXPECT_TRUE(((a * b) * p).isApprox(a * (b * p), 1e-12));
  EXPECT_TRUE((a.Inverse() * (a * p)).isApprox(p, 1e-12));
  const Sim3 id = a * a.Inverse();
  EXPECT_NEAR(id.scale, 1.0, 1e-12);
  EXPECT_TRUE(id.T.matrix().isApprox(Pose::Identity().matrix(), 1e-12));
}

// A monocular loop: 40 keyframes on a circle, whose odometry (the window BA) holds the shape but
// lets the scale grow by 2 % per keyframe (each edge is measured in the units of its first
// keyframe and claims scale ratio 1). The loop edge from the last keyframe to the first carries
// the true relative pose and the scale ratio. The Sim(3) graph must undo the scale drift.
TEST(Sim3PoseGraphTest, LoopClosureUndoesScaleDrift) {
  const int n = 40;
  std::vector<Pose> gt;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    gt.push_back(MakePose(Eigen::Matrix3d(Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY())),
                          Eigen::Vector3d(10.0 * std::sin(a), 0.0, 10.0 * std::cos(a))));
  }
  // units per metre of keyframe i's neighbourhood.
  auto lambda = [](int i) { return std::pow(1.02, i); };
  Matrix7d info = Matrix7d::Identity();
  info.diagonal() << Eigen::Vector3d::Constant(1e6), Eigen::Vector3d::Constant(1e4), 1e4;
  std::vector<Sim3Edge> edges;
  std::map<KeyframeId, Sim3> initial;
  initial[KeyframeId(0)] = Sim3{gt[0], 1.0};
  for (int i = 1; i < n; ++i) {
    Sim3 meas;
    meas.T = gt[i - 1].inverse() * gt[i];
    meas.T.translation() *= lambda(i - 1);
    edges.push_back({KeyframeId(i - 1), KeyframeId(i), meas, info, false});
    initial[KeyframeId(i)] = initial[KeyframeId(i - 1)] * meas;
  }
  Sim3 loop;
  loop.T = gt[n - 1].inverse() * gt[0];
  loop.T.translation() *= lambda(n - 1);
  loop.scale = lambda(n - 1) / lambda(0);
  edges.push_back({KeyframeId(n - 1), KeyframeId(0), loop, info, true});

  auto error = [&](const std::map<KeyframeId, Sim3>& nodes) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      sum += (nodes.at(KeyframeId(i)).T.translation() - gt[i].translation()).squaredNorm();
    }
    return std::sqrt(sum / n);
  };
  PoseGraphSummary summary;
  const auto corrected = OptimizeSim3PoseGraph(initial, edges, PoseGraphOptions(), &summary);
  ASSERT_TRUE(summary.usable);
  const double before = error(initial), after = error(corrected);
  EXPECT_GT(before, 5.0);
  EXPECT_LT(after, 0.05 * before) << "before " << before << " after " << after;
  // Keyframe k maps its own units to metres: s_k = 1 / lambda(k).
  for (int i : {10, 20, n - 1}) {
    EXPECT_NEAR(corrected.at(KeyframeId(i)).scale * lambda(i), 1.0, 0.05) << "keyframe " << i;
  }
  EXPECT_DOUBLE_EQ(corrected.at(KeyframeId(0)).scale, 1.0);  // gauge held.
}

TEST(Sim3PoseGraphTest, ConsistentEdgesAreAFixedPoint) {
  std::mt19937 rng(1);
  std::map<KeyframeId, Sim3> nodes;
  std::vector<Sim3Edge> edges;
  for (int i = 0; i < 5; ++i) nodes[KeyframeId(i)] = RandomSim3(rng);
  for (int i = 1; i < 5; ++i) {
    edges.push_back({KeyframeId(i - 1), KeyframeId(i),
                     nodes[KeyframeId(i - 1)].Inverse() * nodes[KeyframeId(i)],
                     Matrix7d::Identity(), false});
  }
  const auto out = OptimizeSim3PoseGraph(nodes, edges, PoseGraphOptions());
  for (const auto& [id, S] : nodes) {
    EXPECT_POSE_NEAR(out.at(id).T, S.T, 1e-9);
    EXPECT_NEAR(out.at(id).scale, S.scale, 1e-9);
  }
}

}  // namespace
}  // namespace dala
