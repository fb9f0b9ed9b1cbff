#include "backend/ba/reprojection_factors.h"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <vector>

#include "backend/ba/pose_block.h"
#include "tests/test_util.h"

namespace dala {
namespace {

const StereoIntrinsics kK{450.0, 440.0, 320.0, 240.0, 0.5};

// The analytic Jacobians against central differences in the manifold tangent
// (ceres::GradientChecker: pose on the pose manifold, point in R^3), at random poses and points
// in front of the camera; zero residual at the exact projection; whitening by sigma.
// The stereo cost with the disparity offset as a parameter: zero at the true projection of a
// rig with that offset, Jacobians (pose, point, offset) against central differences.
TEST(ReprojectionFactorsTest, DisparityOffsetCostJacobiansMatchNumericDiff) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const auto pose_manifold = MakePoseManifold();
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr, nullptr};
  for (int trial = 0; trial < 10; ++trial) {
    const Pose T_w_c = testing::RandomPose(rng, 0.5, 2.0);
    const Eigen::Vector3d p_c(3.0 * uni(rng), 2.0 * uni(rng), 6.0 + 4.0 * uni(rng));
    Eigen::Vector3d p_w = T_w_c * p_c;
    PoseBlock x = PoseToBlock(T_w_c);
    double offset = 0.3 * uni(rng);
    const double* params[3] = {x.data(), p_w.data(), &offset};
    BaObservation obs;
    obs.uv = Eigen::Vector2d(kK.fx * p_c.x() / p_c.z() + kK.cx, kK.fy * p_c.y() / p_c.z() + kK.cy);
    obs.u_right = obs.uv.x() - kK.fx * kK.baseline / p_c.z() + offset;
    obs.sigma_px = 0.7;
    const std::unique_ptr<ceres::CostFunction> cost(CreateStereoOffsetCost(kK, obs));
    Eigen::Vector3d r;
    ASSERT_TRUE(cost->Evaluate(params, r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-8);
    ceres::NumericDiffOptions numeric;
    ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
  }
}

TEST(ReprojectionFactorsTest, AnalyticJacobiansMatchNumericDiffAndResidualIsZeroAtTruth) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  const auto pose_manifold = MakePoseManifold();
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr};
  for (int trial = 0; trial < 20; ++trial) {
    const Pose T_w_c = testing::RandomPose(rng, 0.5, 2.0);
    const Eigen::Vector3d p_c(3.0 * uni(rng), 2.0 * uni(rng), 6.0 + 4.0 * uni(rng));
    Eigen::Vector3d p_w = T_w_c * p_c;
    PoseBlock x = PoseToBlock(T_w_c);
    const double* params[2] = {x.data(), p_w.data()};
    BaObservation obs;
    obs.uv = Eigen::Vector2d(kK.fx * p_c.x() / p_c.z() + kK.cx, kK.fy * p_c.y() / p_c.z() + kK.cy);
    obs.u_right = obs.uv.x() - kK.fx * kK.baseline / p_c.z();
    obs.sigma_px = 0.7;
    for (bool stereo : {true, false}) {
      BaObservation o = obs;
      if (!stereo) o.u_right.reset();
      const std::unique_ptr<ceres::CostFunction> cost(CreateReprojectionCost(kK, o));
      ASSERT_EQ(cost->num_residuals(), stereo ? 3 : 2);
      Eigen::Vector3d r = Eigen::Vector3d::Zero();
      ASSERT_TRUE(cost->Evaluate(params, r.data(), nullptr));
      EXPECT_LT(r.norm(), 1e-8);
      ceres::NumericDiffOptions numeric;
      ceres::GradientChecker checker(cost.get(), &manifolds, numeric);
      ceres::GradientChecker::ProbeResults results;
      EXPECT_TRUE(checker.Probe(params, 1e-7, &results)) << results.error_log;
      // Pixel offsets of sigma in u, v and u_r: whitened squared residuals 1, 1 and 1.
      double depth = 0.0;
      BaObservation shifted = o;
      shifted.uv.x() += o.sigma_px;
      EXPECT_NEAR(WhitenedSquaredError(kK, shifted, x.data(), p_w.data(), &depth), 1.0, 1e-9);
      EXPECT_NEAR(depth, p_c.z(), 1e-9);
      shifted = o;
      shifted.uv.y() += o.sigma_px;
      EXPECT_NEAR(WhitenedSquaredError(kK, shifted, x.data(), p_w.data(), nullptr), 1.0, 1e-9);
      if (stereo) {
        shifted = o;
        *shifted.u_right += o.sigma_px;
        EXPECT_NEAR(WhitenedSquaredError(kK, shifted, x.data(), p_w.data(), nullptr), 1.0, 1e-9);
        // Offsets (1, 2, 3) sigma together: 1 + 4 + 9.
        shifted.uv += Eigen::Vector2d(1.0, 2.0) * o.sigma_px;
        *shifted.u_right += 2.0 * o.sigma_px;
        EXPECT_NEAR(WhitenedSquaredError(kK, shifted, x.data(), p_w.data(), nullptr), 14.0, 1e-8);
      }
    }
  }
}

TEST(ReprojectionFactorsTest, MonoObservationWithStereoCameraUsesTwoResiduals) {
  BaObservation obs;
  EXPECT_EQ(ResidualDof(kK, obs), 2);
  obs.u_right = 100.0;
  EXPECT_EQ(ResidualDof(kK, obs), 3);
  StereoIntrinsics mono = kK;
  mono.baseline = 0.0;
  EXPECT_EQ(ResidualDof(mono, obs), 2);  // no baseline: the right column is ignored.
}

}  // namespace
}  // namespace dala
