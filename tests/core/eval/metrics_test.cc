// Closed-form checks of ATE, alignment, RPE and the KITTI segment errors.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/eval/evaluate.h"
#include "tests/core/eval/eval_test_util.h"
#include "tests/test_util.h"

namespace dala {
namespace {

using testing::HelixTrajectory;

EvalOptions Options(AlignmentType alignment) {
  EvalOptions o;
  o.alignment = alignment;
  return o;
}

TEST(Statistics, MatchNumpyDefinitions) {
  const ErrorStatistics s = ComputeStatistics({3.0, 1.0, 4.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // Mean of the two middle values.
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // Population std (ddof = 0).
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(ComputeStatistics({5.0, 1.0, 2.0}).median, 2.0);
  EXPECT_EQ(ComputeStatistics({}).count, 0u);
}

TEST(Ate, ConstantOffsetVanishesWithSe3AndEqualsOffsetWithout) {
  const Trajectory gt = HelixTrajectory(200);
  Trajectory est = gt;
  const Eigen::Vector3d offset(0.3, -1.2, 0.4);
  for (StampedPose& p : est.poses) p.T_w_c.translation() += offset;
  const EvalResult se3 = Evaluate(gt, est, Options(AlignmentType::kSE3));
  ASSERT_TRUE(se3.ok) << se3.error;
  EXPECT_EQ(se3.pairs.size(), 200u);
  EXPECT_LT(se3.ate.translation.max, 1e-9);
  EXPECT_LT(se3.ate.rotation_deg.max, 1e-6);
  const EvalResult none = Evaluate(gt, est, Options(AlignmentType::kNone));
  ASSERT_TRUE(none.ok);
  EXPECT_NEAR(none.ate.translation.rmse, offset.norm(), 1e-12);
  EXPECT_NEAR(none.ate.translation.min, offset.norm(), 1e-12);
  EXPECT_NEAR(none.ate.translation.std, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(none.alignment.scale, 1.0);
}

TEST(Ate, RigidlyMovedCopyVanishesWithSe3) {
  std::mt19937 rng(3);
  const Trajectory gt = HelixTrajectory(150);
  const Pose T_e_g = testing::RandomPose(rng, 1.0, 20.0);
  Trajectory est = gt;
  for (StampedPose& p : est.poses) p.T_w_c = T_e_g * p.T_w_c;
  const EvalResult se3 = Evaluate(gt, est, Options(AlignmentType::kSE3));
  ASSERT_TRUE(se3.ok);
  EXPECT_LT(se3.ate.translation.rmse, 1e-8);
  EXPECT_LT(se3.ate.rotation_deg.max, 1e-6);
  EXPECT_POSE_NEAR(se3.alignment.T_g_e, T_e_g.inverse(), 1e-9);
  const EvalResult none = Evaluate(gt, est, Options(AlignmentType::kNone));
  EXPECT_GT(none.ate.translation.rmse, 1.0);
  // Relative errors do not see a rigid transform, aligned or not.
  EXPECT_LT(none.rpe.translation.max, 1e-9);
  EXPECT_LT(none.rpe.rotation_deg.max, 1e-6);
}

TEST(Ate, ScaledCopyVanishesWithSim3Only) {
  const Trajectory gt = HelixTrajectory(150);
  const double s = 2.5;  // The estimate is 2.5 times too large.
  Trajectory est = gt;
  for (StampedPose& p : est.poses) p.T_w_c.translation() *= s;
  const EvalResult sim3 = Evaluate(gt, est, Options(AlignmentType::kSim3));
  ASSERT_TRUE(sim3.ok);
  EXPECT_LT(sim3.ate.translation.rmse, 1e-9);
  // Umeyama maps the estimate onto the ground truth: p_gt = scale * R * p_est + t.
  EXPECT_NEAR(sim3.alignment.scale, 1.0 / s, 1e-12);
  EXPECT_LT(sim3.rpe.translation.max, 1e-9);  // RPE uses the scaled estimate under Sim(3).
  EXPECT_NEAR(sim3.est_path_length_m, sim3.gt_path_length_m, 1e-6);
  const EvalResult se3 = Evaluate(gt, est, Options(AlignmentType::kSE3));
  EXPECT_GT(se3.ate.translation.rmse, 1.0);
  EXPECT_DOUBLE_EQ(se3.alignment.scale, 1.0);
}

TEST(Ate, KnownPerPoseNoiseGivesAnalyticStatistics) {
  const Trajectory gt = HelixTrajectory(100);
  Trajectory est = gt;
  // Errors alternate between 0.1 m along x and 0.2 m along -y.
  for (size_t i = 0; i < est.size(); ++i) {
    est.poses[i].T_w_c.translation() +=
        i % 2 == 0 ? Eigen::Vector3d(0.1, 0, 0) : Eigen::Vector3d(0, -0.2, 0);
  }
  const EvalResult r = Evaluate(gt, est, Options(AlignmentType::kNone));
  ASSERT_TRUE(r.ok);
  EXPECT_NEAR(r.ate.translation.rmse, std::sqrt((0.01 + 0.04) / 2), 1e-12);
  EXPECT_NEAR(r.ate.translation.mean, 0.15, 1e-12);
  EXPECT_NEAR(r.ate.translation.median, 0.15, 1e-12);
  EXPECT_NEAR(r.ate.translation.std, 0.05, 1e-12);
  EXPECT_NEAR(r.ate.translation.max, 0.2, 1e-12);
  ASSERT_EQ(r.ate.translation_errors.size(), 100u);
  EXPECT_NEAR(r.ate.translation_errors[1], 0.2, 1e-12);
  // Alignment can only reduce the least-squares error.
  const EvalResult se3 = Evaluate(gt, est, Options(AlignmentType::kSE3));
  EXPECT_LT(se3.ate.translation.rmse, r.ate.translation.rmse);
}

TEST(Ate, RotationErrorIsTheAngleOfTheRelativeRotation) {
  const Trajectory gt = HelixTrajectory(50);
  Trajectory est = gt;
  const double angle = 0.1;
  for (StampedPose& p : est.poses) p.T_w_c.linear() = p.T_w_c.linear() * ExpSO3({0, 0, angle});
  const EvalResult r = Evaluate(gt, est, Options(AlignmentType::kNone));
  EXPECT_NEAR(r.ate.rotation_deg.rmse, angle * 180 / M_PI, 1e-9);
  EXPECT_LT(r.ate.translation.max, 1e-12);
}

TEST(Alignment, DegenerateInputsAreAStatus) {
  Trajectory two;
  two.Add(0, Pose::Identity());
  two.Add(100000000, MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1, 0, 0)));
  const EvalResult r = Evaluate(two, two, Options(AlignmentType::kSE3));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("at least 3"), std::string::npos) << r.error;
  EXPECT_TRUE(Evaluate(two, two, Options(AlignmentType::kNone)).ok);
  Trajectory still;
  for (int i = 0; i < 5; ++i) still.Add(i * 100000000LL, Pose::Identity());
  EXPECT_FALSE(Evaluate(still, still, Options(AlignmentType::kSim3)).ok);
  // Rotation in place: the ground truth stands still, a (mono) estimate wanders a little. Sim(3)
  // would shrink it onto one point (scale ~0, ATE ~0): refused; SE(3) still judges it.
  Trajectory wandering;
  for (int i = 0; i < 5; ++i) {
    wandering.Add(i * 100000000LL, MakePose(Eigen::Matrix3d::Identity(),
                                            Eigen::Vector3d(0.01 * i, 0.02 * (i % 2), 0)));
  }
  const EvalResult sim3 = Evaluate(still, wandering, Options(AlignmentType::kSim3));
  EXPECT_FALSE(sim3.ok);
  EXPECT_NE(sim3.error.find("do not move"), std::string::npos) << sim3.error;
  const EvalResult se3 = Evaluate(still, wandering, Options(AlignmentType::kSE3));
  ASSERT_TRUE(se3.ok) << se3.error;
  EXPECT_GT(se3.ate.translation.rmse, 0.01);
}

// Per-step drift D: Q_{i+1} = Q_i * G_i * D, so (P_i^-1 P_{i+1})^-1 (Q_i^-1 Q_{i+1}) = D.
TEST(Rpe, ConstantPerStepDrift) {
  const Trajectory gt = HelixTrajectory(101);
  const Pose D = MakePose(ExpSO3({0.0, 0.01, 0.0}), Eigen::Vector3d(0.02, 0.0, 0.01));
  Trajectory est = gt;
  for (size_t i = 1; i < est.size(); ++i) {
    const Pose G = gt.poses[i - 1].T_w_c.inverse() * gt.poses[i].T_w_c;
    est.poses[i].T_w_c = est.poses[i - 1].T_w_c * G * D;
  }
  const EvalResult r = Evaluate(gt, est, Options(AlignmentType::kSE3));
  ASSERT_TRUE(r.ok && r.has_rpe);
  EXPECT_EQ(r.rpe.index_pairs.size(), 100u);
  EXPECT_NEAR(r.rpe.translation.rmse, D.translation().norm(), 1e-9);
  EXPECT_NEAR(r.rpe.translation.min, D.translation().norm(), 1e-9);
  EXPECT_NEAR(r.rpe.rotation_deg.rmse, 0.01 * 180 / M_PI, 1e-7);
  // The drift accumulates: the absolute error grows far beyond one step's error.
  EXPECT_GT(r.ate.translation.max, 10 * D.translation().norm());
}

TEST(Rpe, PairsFollowEvoConsecutiveMode) {
  // A straight line with 0.5 m steps.
  std::vector<Pose> line;
  for (int i = 0; i < 23; ++i) {
    line.push_back(MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 0.5 * i)));
  }
  const auto frames = RpeIndexPairs(line, 10, DeltaUnit::kFrames);
  ASSERT_EQ(frames.size(), 2u);  // ids 0, 10, 20.
  EXPECT_EQ(frames[0], std::make_pair(size_t{0}, size_t{10}));
  EXPECT_EQ(frames[1], std::make_pair(size_t{10}, size_t{20}));
  // Metres: an id each time 2 m of path accumulate, counted from pose 0: 4, 8, 12, 16, 20.
  const auto metres = RpeIndexPairs(line, 2.0, DeltaUnit::kMetres);
  ASSERT_EQ(metres.size(), 4u);
  EXPECT_EQ(metres[0], std::make_pair(size_t{4}, size_t{8}));
  EXPECT_EQ(metres[3], std::make_pair(size_t{16}, size_t{20}));
  EXPECT_TRUE(RpeIndexPairs(line, 30, DeltaUnit::kFrames).empty());
  RpeResult rpe;
  EXPECT_FALSE(ComputeRpe(line, line, 100.0, DeltaUnit::kMetres, &rpe));
}

// A straight 1 km path with 1 m steps; the estimate is 1% too long. Segment (f, L) ends at
// l = f + L + 1 (first distance strictly above L), so t_err = 0.01 (L + 1) / L.
TEST(KittiSegments, StraightKilometreWithScaleError) {
  std::vector<Pose> gt, est;
  for (int i = 0; i <= 1000; ++i) {
    gt.push_back(MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, i)));
    est.push_back(MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1.01 * i)));
  }
  KittiSegmentResult k;
  ASSERT_TRUE(ComputeKittiSegmentErrors(gt, est, KittiSegmentOptions(), &k));
  double sum = 0.0;
  size_t count = 0;
  for (int f = 0; f <= 1000; f += 10) {
    for (int L = 100; L <= 800; L += 100) {
      if (f + L + 1 > 1000) continue;
      sum += 0.01 * (L + 1) / L;
      ++count;
    }
  }
  EXPECT_EQ(k.segments.size(), count);
  EXPECT_NEAR(k.t_err_percent, 100.0 * sum / count, 1e-9);
  EXPECT_NEAR(k.t_err_percent, 1.0, 0.01);  // About the 1% scale error.
  EXPECT_NEAR(k.r_err_deg_per_100m, 0.0, 1e-9);
  ASSERT_EQ(k.per_length.size(), 8u);
  EXPECT_EQ(k.per_length.back().count, 20u);  // 800 m: first frames 0..190.
  EXPECT_EQ(k.segments.front().last, 101u);
  EXPECT_NEAR(k.per_length[0].t_err_percent, 1.01, 1e-9);
}

TEST(KittiSegments, RotationErrorPerMetreAndRigidInvariance) {
  // The estimate turns by 0.001 rad about y after every metre on a straight ground truth.
  std::vector<Pose> gt, est;
  Pose T = Pose::Identity();
  const Pose step = MakePose(ExpSO3({0, 0.001, 0}), Eigen::Vector3d(0, 0, 1));
  for (int i = 0; i <= 300; ++i) {
    gt.push_back(MakePose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, i)));
    est.push_back(T);
    T = T * step;
  }
  KittiSegmentResult k;
  ASSERT_TRUE(ComputeKittiSegmentErrors(gt, est, KittiSegmentOptions(), &k));
  // Segment of length L spans L + 1 steps: angle 0.001 (L + 1) rad.
  EXPECT_NEAR(k.segments.front().r_err_rad_per_m, 0.001 * 101 / 100, 1e-9);
  // Moving the whole estimate rigidly (e.g. not starting at identity) changes nothing.
  std::mt19937 rng(5);
  const Pose M = testing::RandomPose(rng);
  std::vector<Pose> moved;
  for (const Pose& p : est) moved.push_back(M * p);
  KittiSegmentResult k2;
  ASSERT_TRUE(ComputeKittiSegmentErrors(gt, moved, KittiSegmentOptions(), &k2));
  EXPECT_NEAR(k2.t_err_percent, k.t_err_percent, 1e-9);
  EXPECT_NEAR(k2.r_err_deg_per_100m, k.r_err_deg_per_100m, 1e-9);
  // Under 100 m of path there is no segment.
  gt.resize(100);
  est.resize(100);
  EXPECT_FALSE(ComputeKittiSegmentErrors(gt, est, KittiSegmentOptions(), &k));
}

TEST(EvalOptions, IsValidRejectsBadValues) {
  std::string why;
  EXPECT_TRUE(EvalOptions().IsValid(&why));
  EvalOptions o;
  o.max_time_diff_s = -1;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("max_time_diff"), std::string::npos);
  o = EvalOptions();
  o.rpe_delta = 1.5;
  EXPECT_FALSE(o.IsValid(&why));
  o.rpe_delta_unit = DeltaUnit::kMetres;
  EXPECT_TRUE(o.IsValid(&why));
  o.rpe_delta = 0;
  EXPECT_FALSE(o.IsValid(&why));
}

// A straight drive (KITTI-like: 60 m, a few cm of lateral wiggle): positions cannot fix the
// aligned roll about the path, and the result says so; a helix (3D spread) and an unaligned
// evaluation do not get the warning.
TEST(EvalWarnings, StraightPathRotationAboutThePathIsFlagged) {
  Trajectory gt, est;
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector3d p(0.03 * std::sin(0.3 * i), 0.02 * std::cos(0.2 * i), 1.0 * i);
    gt.Add(i * 100000000LL, MakePose(Eigen::Quaterniond::Identity(), p));
    est.Add(i * 100000000LL, MakePose(Eigen::Quaterniond::Identity(),
                                      p + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))));
  }
  const EvalResult straight = Evaluate(gt, est, EvalOptions());
  ASSERT_TRUE(straight.ok) << straight.error;
  ASSERT_EQ(straight.warnings.size(), 1u);
  EXPECT_NE(straight.warnings[0].find("almost on a line"), std::string::npos);
  EXPECT_EQ(EvalResultToJson(straight).at("warnings").size(), 1u);
  EXPECT_NE(EvalResultToTable(straight).find("note: "), std::string::npos);

  EvalOptions unaligned;
  unaligned.alignment = AlignmentType::kNone;
  EXPECT_TRUE(Evaluate(gt, est, unaligned).warnings.empty());

  const Trajectory helix = HelixTrajectory(60);
  const EvalResult spread = Evaluate(helix, helix, EvalOptions());
  ASSERT_TRUE(spread.ok);
  EXPECT_TRUE(spread.warnings.empty());
  EXPECT_TRUE(EvalResultToJson(spread).at("warnings").empty());
}

TEST(EvalJson, HasTheDocumentedKeys) {
  const Trajectory gt = HelixTrajectory(60);
  const EvalResult r = Evaluate(gt, gt, EvalOptions());
  const nlohmann::json j = EvalResultToJson(r);
  EXPECT_EQ(j.at("pairs").get<size_t>(), 60u);
  for (const char* key : {"rmse", "mean", "median", "max", "std", "min"}) {
    EXPECT_TRUE(j.at("ate").contains(key)) << key;
  }
  EXPECT_TRUE(j.at("rpe").contains("trans_rmse"));
  EXPECT_TRUE(j.at("rpe").contains("rot_rmse_deg"));
  EXPECT_DOUBLE_EQ(j.at("scale").get<double>(), 1.0);
  EXPECT_EQ(j.at("alignment").get<std::string>(), "se3");
  EXPECT_FALSE(j.contains("kitti"));  // 60 poses of a 30 m helix: too short.
  EvalResult failed;
  failed.error = "no pairs";
  EXPECT_EQ(EvalResultToJson(failed).at("error").get<std::string>(), "no pairs");
}

}  // namespace
}  // namespace dala
