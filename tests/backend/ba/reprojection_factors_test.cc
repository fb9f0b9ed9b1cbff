#include "backend/ba/reprojection_factors.h"

#include <ceres/numeric_diff_cost_function.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "backend/ba/pose_block.h"
#include "tests/test_util.h"

namespace dala {
namespace {

const StereoIntrinsics kK{450.0, 440.0, 320.0, 240.0, 0.5};

// Evaluates residuals and ambient Jacobians (pose 7, point 3) of a cost function.
void EvaluateCost(const ceres::CostFunction& cost, PoseBlock& x, Eigen::Vector3d& p,
                  Eigen::VectorXd* r, Eigen::MatrixXd* J_x, Eigen::MatrixXd* J_p) {
  const int m = cost.num_residuals();
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> jx(m, 7);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> jp(m, 3);
  double* params[2] = {x.data(), p.data()};
  double* jacs[2] = {jx.data(), jp.data()};
  r->resize(m);
  ASSERT_TRUE(cost.Evaluate(params, r->data(), jacs));
  *J_x = jx;
  *J_p = jp;
}

// Autodiff Jacobians against central differences of the same functor, at random poses and
// points in front of the camera; and zero residual at the exact projection.
TEST(ReprojectionFactorsTest, AutodiffMatchesNumericDiffAndResidualIsZeroAtTruth) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose T_w_c = testing::RandomPose(rng, 0.5, 2.0);
    const Eigen::Vector3d p_c(3.0 * uni(rng), 2.0 * uni(rng), 6.0 + 4.0 * uni(rng));
    Eigen::Vector3d p_w = T_w_c * p_c;
    PoseBlock x = PoseToBlock(T_w_c);
    BaObservation obs;
    obs.uv = Eigen::Vector2d(kK.fx * p_c.x() / p_c.z() + kK.cx, kK.fy * p_c.y() / p_c.z() + kK.cy);
    obs.u_right = obs.uv.x() - kK.fx * kK.baseline / p_c.z();
    obs.sigma_px = 0.7;
    for (bool stereo : {true, false}) {
      BaObservation o = obs;
      if (!stereo) o.u_right.reset();
      std::unique_ptr<ceres::CostFunction> autodiff(CreateReprojectionCost(kK, o));
      std::unique_ptr<ceres::CostFunction> numeric;
      if (stereo) {
        numeric.reset(
            new ceres::NumericDiffCostFunction<StereoReprojectionError, ceres::CENTRAL, 3, 7, 3>(
                new StereoReprojectionError(kK, o.uv, *o.u_right, o.sigma_px)));
      } else {
        numeric.reset(
            new ceres::NumericDiffCostFunction<MonoReprojectionError, ceres::CENTRAL, 2, 7, 3>(
                new MonoReprojectionError(kK, o.uv, o.sigma_px)));
      }
      EXPECT_EQ(autodiff->num_residuals(), stereo ? 3 : 2);
      Eigen::VectorXd ra, rn;
      Eigen::MatrixXd Jxa, Jpa, Jxn, Jpn;
      EvaluateCost(*autodiff, x, p_w, &ra, &Jxa, &Jpa);
      EvaluateCost(*numeric, x, p_w, &rn, &Jxn, &Jpn);
      EXPECT_LT(ra.norm(), 1e-8);
      EXPECT_LT((Jxa - Jxn).norm(), 1e-5 * (1.0 + Jxa.norm())) << "\n" << Jxa << "\n" << Jxn;
      EXPECT_LT((Jpa - Jpn).norm(), 1e-5 * (1.0 + Jpa.norm()));
      // A pixel offset of sigma in u gives a whitened residual of 1.
      BaObservation shifted = o;
      shifted.uv.x() += o.sigma_px;
      double depth = 0.0;
      EXPECT_NEAR(WhitenedSquaredError(kK, shifted, x.data(), p_w.data(), &depth), 1.0, 1e-9);
      EXPECT_NEAR(depth, p_c.z(), 1e-9);
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
