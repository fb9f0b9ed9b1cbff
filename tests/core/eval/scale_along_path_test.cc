// The scale along the path (core/eval/scale_along_path.h) against trajectories whose scale is
// known piece by piece.
#include "core/eval/scale_along_path.h"

#include <gtest/gtest.h>

#include "tests/core/eval/eval_test_util.h"

namespace dala {
namespace {

EvalOptions Sim3Options() {
  EvalOptions o;
  o.alignment = AlignmentType::kSim3;
  return o;
}

// A whole copy in another world and unit: every segment has the run's scale (r_k = 1).
TEST(ScaleAlongPath, ASimilarCopyHasOneScaleEverywhere) {
  const Trajectory gt = testing::HelixTrajectory(200);
  Trajectory est;
  const Pose T = MakePose(ExpSO3(Eigen::Vector3d(0.3, -0.2, 1.0)), Eigen::Vector3d(4, -2, 7));
  for (const StampedPose& p : gt.poses) {
    Pose q = T * p.T_w_c;
    q.translation() *= 0.37;
    est.Add(p.t_ns, q);
  }
  const EvalResult r = Evaluate(gt, est, Sim3Options());
  ASSERT_TRUE(r.ok) << r.error;
  const ScaleAlongPath s = MeasureScaleAlongPath(r, 10);
  ASSERT_EQ(s.segments.size(), 10u);
  EXPECT_NEAR(s.min, 1.0, 1e-6);
  EXPECT_NEAR(s.max, 1.0, 1e-6);
  EXPECT_NEAR(s.segment_m * 10, r.pair_distance_m.back(), 1e-9);
  EXPECT_EQ(s.segments.front().first_pair, 0u);
  EXPECT_EQ(s.segments.back().last_pair, r.pairs.size() - 1);
}

// The estimate's steps 20 % longer in the second half (a scale that drifts at half way): the
// second half's segments are 1.2x the first half's, whatever the run's alignment made of both.
TEST(ScaleAlongPath, AScaleStepAtHalfWayShowsInTheSegments) {
  const Trajectory gt = testing::HelixTrajectory(200);
  Trajectory est;
  Eigen::Vector3d p = gt.poses[0].T_w_c.translation();
  for (size_t i = 0; i < gt.size(); ++i) {
    if (i > 0) {
      const Eigen::Vector3d step =
          gt.poses[i].T_w_c.translation() - gt.poses[i - 1].T_w_c.translation();
      // 199 equal steps: the half-way boundary (99.5 steps) falls between poses 99 and 100,
      // where the segments 1 and 2 meet (both hold pose 99): the steps from pose 100 on.
      p += (i >= 100 ? 1.2 : 1.0) * step;
    }
    Pose q = gt.poses[i].T_w_c;
    q.translation() = p;
    est.Add(gt.poses[i].t_ns, q);
  }
  const EvalResult r = Evaluate(gt, est, Sim3Options());
  ASSERT_TRUE(r.ok) << r.error;
  const ScaleAlongPath s = MeasureScaleAlongPath(r, 4);
  ASSERT_EQ(s.segments.size(), 4u);
  // Segments 0-1 lie in the first half, 2-3 in the second (equal ground-truth lengths).
  EXPECT_NEAR(s.segments[0].relative_scale, s.segments[1].relative_scale, 1e-6);
  EXPECT_NEAR(s.segments[2].relative_scale, s.segments[3].relative_scale, 1e-6);
  EXPECT_NEAR(s.segments[2].relative_scale / s.segments[0].relative_scale, 1.2, 1e-3);
  EXPECT_NEAR(s.max / s.min, 1.2, 1e-3);
  // The run's alignment takes a scale between the two.
  EXPECT_LT(s.min, 1.0);
  EXPECT_GT(s.max, 1.0);
}

// SE(3): r_k is the estimate's scale error itself.
TEST(ScaleAlongPath, Se3GivesTheScaleErrorItself) {
  const Trajectory gt = testing::HelixTrajectory(100);
  Trajectory est;
  for (const StampedPose& p : gt.poses) {
    Pose q = p.T_w_c;
    q.translation() *= 1.03;
    est.Add(p.t_ns, q);
  }
  EvalOptions o;
  o.alignment = AlignmentType::kSE3;
  const EvalResult r = Evaluate(gt, est, o);
  ASSERT_TRUE(r.ok) << r.error;
  const ScaleAlongPath s = MeasureScaleAlongPath(r, 5);
  ASSERT_EQ(s.segments.size(), 5u);
  EXPECT_NEAR(s.min, 1.03, 1e-6);
  EXPECT_NEAR(s.max, 1.03, 1e-6);
}

TEST(ScaleAlongPath, NoSegmentsSaysWhy) {
  EvalResult failed;
  const ScaleAlongPath s = MeasureScaleAlongPath(failed, 10);
  EXPECT_TRUE(s.segments.empty());
  EXPECT_FALSE(s.note.empty());
  EXPECT_TRUE(ScaleAlongPathToJson(s).contains("note"));
}

}  // namespace
}  // namespace dala
