#include "backend/ba/global_ba.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "backend/ba/sliding_window_ba.h"
#include "tests/backend/ba/ba_synthetic_scene.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::AlignedAte;
using testing::BaScene;
using testing::BaSceneOptions;
using testing::MakeBaScene;
using testing::PerturbPose;

// RMS distance of the keyframe positions from the ground truth, without any alignment (the
// held keyframes carry the gauge, at their true poses).
double PositionRmse(const std::map<KeyframeId, Pose>& est, const std::vector<Pose>& gt) {
  double sum = 0.0;
  for (const auto& [id, T] : est) {
    sum += (T.translation() - gt.at(id.value).translation()).squaredNorm();
  }
  return std::sqrt(sum / est.size());
}

// The problem as a run leaves it: poses chained from noisy relative motions (they drift),
// landmarks off by `point_noise_m`, the first `num_held` keyframes at their true poses.
GlobalBaProblem DriftedProblem(const BaScene& scene, int num_held, double point_noise_m,
                               unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, point_noise_m);
  GlobalBaProblem problem;
  Pose T_w_c = scene.T_w_c_gt[0];
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    const KeyframeId id = scene.keyframes[i].id;
    if (static_cast<int>(i) < num_held) {
      T_w_c = scene.T_w_c_gt[i];
      problem.held.insert(id);
    } else {
      T_w_c = T_w_c *
              PerturbPose(scene.T_w_c_gt[i - 1].inverse() * scene.T_w_c_gt[i], rng, 0.004, 0.02);
    }
    problem.keyframes[id] = T_w_c;
    for (const BaObservation& o : scene.keyframes[i].observations) {
      problem.observations.emplace_back(id, o);
    }
  }
  for (size_t j = 0; j < scene.p_w_gt.size(); ++j) {
    problem.landmarks[LandmarkId(static_cast<int64_t>(j))] =
        scene.p_w_gt[j] + Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  return problem;
}

BaSceneOptions Scene(bool stereo) {
  BaSceneOptions o;
  o.num_keyframes = 30;
  o.num_points = 400;
  o.stereo = stereo;
  return o;
}

TEST(GlobalBaTest, StereoUndoesTheDriftOfChainedMotions) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/true));
  GlobalBaProblem problem = DriftedProblem(scene, 1, 0.1, 3);
  const double before = PositionRmse(problem.keyframes, scene.T_w_c_gt);
  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem);
  ASSERT_TRUE(s.usable) << s.BriefReport();
  const double after = PositionRmse(problem.keyframes, scene.T_w_c_gt);
  EXPECT_GT(before, 0.05);
  EXPECT_LT(after, 0.01) << s.BriefReport();
  EXPECT_EQ(s.num_keyframes, 30);
  EXPECT_LT(s.final_cost, s.initial_cost);
  // The held keyframe has not moved.
  EXPECT_TRUE(problem.keyframes.at(KeyframeId(0)).isApprox(scene.T_w_c_gt[0], 1e-12));
}

TEST(GlobalBaTest, MonoTakesItsUnitFromTheTwoHeldKeyframes) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/false));
  GlobalBaProblem problem = DriftedProblem(scene, 2, 0.1, 4);
  const double before = PositionRmse(problem.keyframes, scene.T_w_c_gt);
  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem);
  ASSERT_TRUE(s.usable) << s.BriefReport();
  // No Sim(3) alignment: the two held keyframes fix the pose and the unit of the map.
  const double after = PositionRmse(problem.keyframes, scene.T_w_c_gt);
  std::vector<Pose> est;
  for (const auto& [id, T] : problem.keyframes) est.push_back(T);
  const double shape = AlignedAte(est, scene.T_w_c_gt, /*with_scale=*/true);
  std::cout << "[ measured ] mono global BA: " << before << " m before, " << after
            << " m after (unaligned), " << shape << " m after a Sim(3) alignment" << std::endl;
  // The shape is recovered and the unit is the held pair's (0.6 m apart, observed with 0.5 px
  // noise).
  EXPECT_GT(before, 0.2);
  testing::ExpectWithinBound("ba/mono global BA, geometric scene, keyframe error unaligned", after,
                             0.0396, "m");
  testing::ExpectWithinBound("ba/mono global BA, geometric scene, keyframe error after Sim(3)",
                             shape, 0.00456, "m");
}

TEST(GlobalBaTest, IsAtLeastAsGoodAsTheSlidingWindowItStartsFrom) {
  // The online use: a window of 6 over the scene, then the global BA from its estimates.
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/true));
  SlidingWindowBa::Options options;
  options.window_size = 6;
  SlidingWindowBa ba(scene.K, options);
  GlobalBaProblem problem = DriftedProblem(scene, 1, 0.1, 5);
  std::map<KeyframeId, Pose> window_estimate;
  for (size_t i = 0; i < scene.keyframes.size(); ++i) {
    BaKeyframe kf = scene.keyframes[i];
    kf.T_w_c = i == 0 ? scene.T_w_c_gt[0]
                      : window_estimate.at(scene.keyframes[i - 1].id) *
                            (problem.keyframes.at(scene.keyframes[i - 1].id).inverse() *
                             problem.keyframes.at(kf.id));
    ba.AddKeyframe(kf);
    ASSERT_TRUE(ba.Optimize().usable);
    for (KeyframeId id : ba.WindowKeyframes()) window_estimate[id] = *ba.KeyframePose(id);
  }
  for (const auto& [id, p_w] : ba.Landmarks()) problem.landmarks[id] = p_w;
  problem.keyframes = window_estimate;
  const double window_error = PositionRmse(window_estimate, scene.T_w_c_gt);
  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem);
  ASSERT_TRUE(s.usable) << s.BriefReport();
  const double global_error = PositionRmse(problem.keyframes, scene.T_w_c_gt);
  EXPECT_LT(global_error, window_error) << "window " << window_error << " m";
}

TEST(GlobalBaTest, RemovesGrossOutliersAndIgnoresWhatItCannotUse) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/true));
  GlobalBaProblem problem = DriftedProblem(scene, 1, 0.05, 6);
  // Ten observations moved by 40 px: wrong matches.
  std::vector<std::pair<KeyframeId, LandmarkId>> wrong;
  for (size_t i = 0; i < 10; ++i) {
    auto& o = problem.observations[i * 97 + 11];
    o.second.uv += Eigen::Vector2d(40.0, -25.0);
    wrong.emplace_back(o.first, o.second.landmark);
  }
  // An observation of a keyframe that does not exist and of a landmark without a position, and
  // a landmark seen by one keyframe only: skipped, not an error.
  BaObservation stray = scene.keyframes[3].observations[0];
  problem.observations.emplace_back(KeyframeId(999), stray);
  stray.landmark = LandmarkId(123456);
  problem.observations.emplace_back(KeyframeId(3), stray);
  const LandmarkId lone(777777);
  const Eigen::Vector3d lone_p(1.0, 2.0, 30.0);
  problem.landmarks[lone] = lone_p;
  stray.landmark = lone;
  problem.observations.emplace_back(KeyframeId(4), stray);

  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem);
  ASSERT_TRUE(s.usable) << s.BriefReport();
  EXPECT_GE(s.num_outliers_removed, 10);
  for (const auto& [kf, landmark] : wrong) {
    EXPECT_TRUE(
        std::none_of(problem.observations.begin(), problem.observations.end(),
                     [&](const auto& o) { return o.first == kf && o.second.landmark == landmark; }))
        << "keyframe " << kf << " landmark " << landmark;
  }
  EXPECT_LT(PositionRmse(problem.keyframes, scene.T_w_c_gt), 0.01) << s.BriefReport();
  EXPECT_EQ(problem.landmarks.at(lone), lone_p);
  EXPECT_EQ(problem.keyframes.count(KeyframeId(999)), 0u);
}

TEST(GlobalBaTest, NothingToSolveChangesNothing) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/true));
  GlobalBaProblem problem = DriftedProblem(scene, 1, 0.1, 7);
  problem.observations.resize(1);  // One view of one landmark: no residual.
  const auto keyframes = problem.keyframes;
  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem);
  EXPECT_TRUE(s.usable);
  EXPECT_EQ(s.num_solves, 0);
  for (const auto& [id, T] : keyframes) EXPECT_TRUE(problem.keyframes.at(id).isApprox(T, 0.0));
}

// A stop request ends the refinement wherever it is (before the first solve, or between two
// iterations of one) and changes nothing: the run's own estimates stay, as after a failed solve.
TEST(GlobalBaTest, AStopRequestEndsItAndChangesNothing) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/true));
  for (const int polls_before_stop : {0, 3}) {
    GlobalBaProblem problem = DriftedProblem(scene, 1, 0.1, 9);
    const GlobalBaProblem before = problem;
    int polls = 0;
    const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &problem,
                                            [&] { return polls++ >= polls_before_stop; });
    EXPECT_TRUE(s.stopped) << polls_before_stop;
    EXPECT_FALSE(s.usable);
    EXPECT_EQ(s.num_solves, polls_before_stop == 0 ? 0 : 1) << s.BriefReport();
    EXPECT_THAT(s.BriefReport(), ::testing::HasSubstr("stopped on request"));
    for (const auto& [id, T] : before.keyframes) {
      EXPECT_EQ(problem.keyframes.at(id).matrix(), T.matrix()) << id;
    }
    EXPECT_EQ(problem.landmarks, before.landmarks);
  }
  // A request that never comes changes nothing either: the same solution as without one.
  GlobalBaProblem with = DriftedProblem(scene, 1, 0.1, 9), without = with;
  SolveGlobalBa(scene.K, GlobalBaOptions(), &with, [] { return false; });
  const GlobalBaSummary s = SolveGlobalBa(scene.K, GlobalBaOptions(), &without);
  EXPECT_FALSE(s.stopped);
  for (const auto& [id, T] : with.keyframes) {
    EXPECT_EQ(T.matrix(), without.keyframes.at(id).matrix()) << id;
  }
}

TEST(GlobalBaTest, IsDeterministic) {
  const BaScene scene = MakeBaScene(Scene(/*stereo=*/false));
  GlobalBaProblem a = DriftedProblem(scene, 2, 0.1, 8);
  GlobalBaProblem b = a;
  SolveGlobalBa(scene.K, GlobalBaOptions(), &a);
  SolveGlobalBa(scene.K, GlobalBaOptions(), &b);
  for (const auto& [id, T] : a.keyframes) {
    EXPECT_EQ(T.matrix(), b.keyframes.at(id).matrix()) << id;
  }
}

}  // namespace
}  // namespace dala
