#include "core/eval/trajectory_fusion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/geometry.h"
#include "tests/core/eval/eval_test_util.h"

namespace dala {
namespace {

// RMS position error of `est` after its best Sim(3) onto `truth` (same stamps, same order).
double SimilarityAte(const Trajectory& truth, const Trajectory& est) {
  std::vector<Eigen::Vector3d> p_e, p_g;
  for (size_t i = 0; i < est.size(); ++i) {
    p_e.push_back(est.poses[i].T_w_c.translation());
    p_g.push_back(truth.poses[i].T_w_c.translation());
  }
  Sim3Alignment S;
  std::string why;
  EXPECT_TRUE(ComputeAlignment(p_e, p_g, AlignmentType::kSim3, &S, &why)) << why;
  double sq = 0.0;
  for (size_t i = 0; i < p_e.size(); ++i) sq += (S.Apply(p_e[i]) - p_g[i]).squaredNorm();
  return std::sqrt(sq / static_cast<double>(p_e.size()));
}

TEST(FuseTrajectories, OneRunSeenInThreeWorldsFusesToTheFirst) {
  const Trajectory truth = testing::HelixTrajectory(60);
  const std::vector<Trajectory> runs = {
      truth, testing::Transformed(truth, 2.5, {0.3, -0.2, 1.0}, {4, -1, 2}),
      testing::Transformed(truth, 0.4, {-1.2, 0.5, 0.1}, {-3, 0, 7})};
  FusedTrajectory fused;
  std::string why;
  ASSERT_TRUE(FuseTrajectories(runs, TrajectoryFusionOptions(), &fused, &why)) << why;
  ASSERT_EQ(fused.trajectory.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    const Pose& a = truth.poses[i].T_w_c;
    const Pose& b = fused.trajectory.poses[i].T_w_c;
    EXPECT_EQ(fused.trajectory.poses[i].t_ns, truth.poses[i].t_ns);
    EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9);
    EXPECT_LT(LogSO3(a.linear().transpose() * b.linear()).norm(), 1e-9);
    EXPECT_EQ(fused.runs[i], 3);
    EXPECT_LT(fused.spread[i], 1e-9);
  }
  // Each run's alignment undoes its transform: scales 1, 1/2.5, 1/0.4.
  ASSERT_EQ(fused.alignments.size(), 3u);
  EXPECT_NEAR(fused.alignments[0].scale, 1.0, 1e-9);
  EXPECT_NEAR(fused.alignments[1].scale, 1.0 / 2.5, 1e-9);
  EXPECT_NEAR(fused.alignments[2].scale, 1.0 / 0.4, 1e-9);
}

// Runs whose errors are independent (noise on every position and orientation, each run in its
// own world and unit): the mean of five lies nearer the truth than any of them, by about the
// square root of five.
TEST(FuseTrajectories, TheMeanOfRunsWithIndependentErrorsIsNearerTheTruth) {
  const Trajectory truth = testing::HelixTrajectory(80);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  constexpr double kSigmaM = 0.2, kSigmaRad = 0.02;
  std::vector<Trajectory> runs;
  double worst_run = 0.0, best_run = 1e9;
  for (int k = 0; k < 5; ++k) {
    Trajectory run = truth;
    for (StampedPose& p : run.poses) {
      p.T_w_c.translation() += kSigmaM * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      p.T_w_c.linear() = p.T_w_c.linear() *
                         ExpSO3(kSigmaRad * Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
    const double ate = SimilarityAte(truth, run);
    worst_run = std::max(worst_run, ate);
    best_run = std::min(best_run, ate);
    runs.push_back(
        testing::Transformed(run, 0.5 + 0.3 * k, {0.2 * k, -0.1, 0.4}, {1.0 * k, 2.0 * k, -1.0}));
  }
  FusedTrajectory fused;
  std::string why;
  ASSERT_TRUE(FuseTrajectories(runs, TrajectoryFusionOptions(), &fused, &why)) << why;
  ASSERT_EQ(fused.trajectory.size(), truth.size());
  const double fused_ate = SimilarityAte(truth, fused.trajectory);
  std::cout << "[ measured ] ATE of the five runs " << best_run << " to " << worst_run
            << ", of their fusion " << fused_ate << std::endl;
  // sqrt(5) = 2.24: the mean's error is that much smaller, within the sampling of 80 poses.
  EXPECT_LT(fused_ate, best_run / 1.8);
  EXPECT_GT(fused_ate, worst_run / 3.0);
  // The orientations are averaged too: each fused rotation within ~sigma/sqrt(5) of the truth's.
  double sq = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    // The fused world is run 0's: compare with the truth's rotation carried into it. Run 0's
    // world is the truth's under its own transform (scale 0.5, rotation ExpSO3(0, -0.1, 0.4)).
    const Eigen::Matrix3d R_truth =
        ExpSO3(Eigen::Vector3d(0, -0.1, 0.4)) * truth.poses[i].T_w_c.linear();
    sq += LogSO3(R_truth.transpose() * fused.trajectory.poses[i].T_w_c.linear()).squaredNorm();
  }
  const double rot_rms = std::sqrt(sq / static_cast<double>(truth.size()));
  EXPECT_LT(rot_rms, kSigmaRad * std::sqrt(3.0) / 1.8);
}

TEST(FuseTrajectories, AFrameOneRunLacksTakesTheOthersMean) {
  const Trajectory truth = testing::HelixTrajectory(30);
  Trajectory shifted = truth;
  for (StampedPose& p : shifted.poses) p.T_w_c.translation() += Eigen::Vector3d(0.0, 0.0, 0.2);
  Trajectory gap = shifted;
  gap.poses.erase(gap.poses.begin() + 10);  // A frame lost in the second run.
  FusedTrajectory fused;
  std::string why;
  TrajectoryFusionOptions options;
  options.alignment = AlignmentType::kNone;  // Averaged as they are.
  ASSERT_TRUE(FuseTrajectories({truth, gap}, options, &fused, &why)) << why;
  ASSERT_EQ(fused.trajectory.size(), truth.size());
  EXPECT_EQ(fused.runs[10], 1);
  EXPECT_EQ(fused.runs[11], 2);
  EXPECT_NEAR(fused.trajectory.poses[10].T_w_c.translation().z(),
              truth.poses[10].T_w_c.translation().z(), 1e-12);
  EXPECT_NEAR(fused.trajectory.poses[11].T_w_c.translation().z(),
              truth.poses[11].T_w_c.translation().z() + 0.1, 1e-12);
  EXPECT_NEAR(fused.spread[11], 0.1, 1e-12);
}

TEST(FuseTrajectories, RunsThatCannotBeFusedSayWhy) {
  const Trajectory truth = testing::HelixTrajectory(30);
  FusedTrajectory fused;
  std::string why;
  EXPECT_FALSE(FuseTrajectories({}, TrajectoryFusionOptions(), &fused, &why));
  EXPECT_EQ(why, "no run to fuse");
  EXPECT_FALSE(FuseTrajectories({truth, Trajectory()}, TrajectoryFusionOptions(), &fused, &why));
  EXPECT_EQ(why, "run 2 has no pose");
  // Other frames (stamps an hour later): nothing to align on.
  const Trajectory elsewhere = testing::HelixTrajectory(30, 3600000000000LL);
  EXPECT_FALSE(FuseTrajectories({truth, elsewhere}, TrajectoryFusionOptions(), &fused, &why));
  EXPECT_NE(why.find("run 2 shares 0 stamps"), std::string::npos) << why;
  Trajectory rows = truth;
  rows.has_timestamps = false;
  EXPECT_FALSE(FuseTrajectories({truth, rows}, TrajectoryFusionOptions(), &fused, &why));
  EXPECT_NE(why.find("timestamps"), std::string::npos) << why;
}

}  // namespace
}  // namespace dala
