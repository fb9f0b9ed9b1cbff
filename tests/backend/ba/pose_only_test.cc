#include "backend/ba/pose_only.h"

#include <gtest/gtest.h>

#include <map>
#include <random>

#include "tests/backend/ba/ba_synthetic_scene.h"

namespace dala {
namespace {

using testing::BaScene;
using testing::BaSceneOptions;
using testing::MakeBaScene;
using testing::PerturbPose;

LandmarkLookup LookupIn(const BaScene& scene) {
  return [&scene](LandmarkId id) -> std::optional<Eigen::Vector3d> {
    if (id.value < 0 || id.value >= static_cast<int64_t>(scene.p_w_gt.size())) return std::nullopt;
    return scene.p_w_gt[id.value];
  };
}

double RotationErrorDeg(const Pose& a, const Pose& b) {
  return LogSO3(a.rotation().transpose() * b.rotation()).norm() * 180.0 / M_PI;
}

TEST(PoseOnlyTest, RecoversAPerturbedPose) {
  BaSceneOptions so;
  so.num_keyframes = 6;
  const BaScene scene = MakeBaScene(so);
  std::mt19937 rng(2);
  for (int k = 1; k < 6; ++k) {
    const Pose& gt = scene.T_w_c_gt[k];
    const Pose guess = PerturbPose(gt, rng, 0.03, 0.2);
    const PoseOnlyResult res = EstimatePoseOnly(scene.K, scene.keyframes[k].observations,
                                                LookupIn(scene), guess, PoseOnlyOptions());
    ASSERT_EQ(res.status, PoseOnlyStatus::kOk) << PoseOnlyStatusName(res.status);
    EXPECT_LT((res.T_w_c.translation() - gt.translation()).norm(), 0.01);
    EXPECT_LT(RotationErrorDeg(res.T_w_c, gt), 0.1);
    EXPECT_GT((guess.translation() - gt.translation()).norm(), 0.05);
    EXPECT_GT(res.num_inliers, 100);
  }
}

// NEES of the right-perturbation error xi = Log(T_hat^-1 T_true) against the returned
// covariance: chi-square with 6 dof, mean 6, over independent noise draws.
TEST(PoseOnlyTest, CovarianceIsConsistent) {
  double nees_sum = 0.0;
  const int trials = 30;
  PoseOnlyOptions options;
  options.remove_outliers = false;  // keep the chi-square test untruncated.
  for (int t = 0; t < trials; ++t) {
    BaSceneOptions so;
    so.num_keyframes = 3;
    so.num_points = 120;
    so.seed = 100 + t;
    const BaScene scene = MakeBaScene(so);
    std::mt19937 rng(t);
    const Pose& gt = scene.T_w_c_gt[2];
    const PoseOnlyResult res =
        EstimatePoseOnly(scene.K, scene.keyframes[2].observations, LookupIn(scene),
                         PerturbPose(gt, rng, 0.01, 0.1), options);
    ASSERT_EQ(res.status, PoseOnlyStatus::kOk);
    const Vector6d xi = LogSE3(res.T_w_c.inverse() * gt);
    nees_sum += xi.dot(res.covariance.ldlt().solve(xi));
  }
  const double nees = nees_sum / trials;
  // The mean of 30 chi2(6)/... has standard deviation sqrt(12/30) = 0.63.
  EXPECT_GT(nees, 4.0);
  EXPECT_LT(nees, 8.5);
}

TEST(PoseOnlyTest, RejectsOutliersAndIgnoresUnknownLandmarks) {
  BaSceneOptions so;
  so.num_keyframes = 3;
  const BaScene scene = MakeBaScene(so);
  std::vector<BaObservation> obs = scene.keyframes[1].observations;
  std::mt19937 rng(9);
  int injected = 0;
  for (size_t i = 0; i < obs.size(); i += 10, ++injected) obs[i].uv.y() += 30.0;
  BaObservation unknown;
  unknown.landmark = LandmarkId(1000000);
  obs.push_back(unknown);
  const Pose& gt = scene.T_w_c_gt[1];
  const PoseOnlyResult res = EstimatePoseOnly(scene.K, obs, LookupIn(scene),
                                              PerturbPose(gt, rng, 0.01, 0.1), PoseOnlyOptions());
  ASSERT_EQ(res.status, PoseOnlyStatus::kOk);
  EXPECT_GE(res.num_outliers_removed, injected);
  EXPECT_FALSE(res.inliers.back());
  for (size_t i = 0; i < obs.size() - 1; i += 10) EXPECT_FALSE(res.inliers[i]) << i;
  EXPECT_LT((res.T_w_c.translation() - gt.translation()).norm(), 0.01);
}

TEST(PoseOnlyTest, TooFewObservationsIsAStatus) {
  BaSceneOptions so;
  so.num_keyframes = 2;
  const BaScene scene = MakeBaScene(so);
  std::vector<BaObservation> obs(scene.keyframes[0].observations.begin(),
                                 scene.keyframes[0].observations.begin() + 3);
  const PoseOnlyResult res =
      EstimatePoseOnly(scene.K, obs, LookupIn(scene), scene.T_w_c_gt[0], PoseOnlyOptions());
  EXPECT_EQ(res.status, PoseOnlyStatus::kTooFewObservations);
  EXPECT_TRUE(res.T_w_c.isApprox(scene.T_w_c_gt[0]));
}

}  // namespace
}  // namespace dala
