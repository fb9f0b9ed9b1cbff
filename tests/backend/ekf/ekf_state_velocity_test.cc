// EkfState with the velocity (the mono EKF's constant-velocity model): the covariance
// propagation of PredictConstantVelocity against the error propagated through the exact motion.
#include <gtest/gtest.h>

#include "backend/ekf/ekf_state.h"
#include "core/geometry.h"

namespace dala {
namespace {

// A velocity error e_w alone (P0 = e_w e_w^T on the velocity block) must come out of the
// prediction as P1 = e' e'^T, e' the invariant error of the exactly predicted perturbed state
// (pose xi' = Log(T' T_hat'^-1), velocity e_w, landmarks e_i' = J_l(phi')^-1 (p - Exp(phi') p)).
TEST(EkfStateVelocity, PredictionMatchesTheExactlyPropagatedError) {
  const Pose T_hat = ExpSE3((Vector6d() << 0.2, -0.4, 0.3, 1.0, -2.0, 0.5).finished());
  Vector6d w_hat;
  w_hat << 0.3, -0.2, 0.5, 1.0, 0.2, -0.5;
  const double dt = 0.1;
  const Eigen::Vector3d p1(3, -1, 8), p2(-2, 0.5, 4);
  for (int k = 0; k < 6; ++k) {
    Vector6d e_w = Vector6d::Zero();
    e_w(k) = 1e-5;
    e_w((k + 2) % 6) = -0.7e-5;
    EkfState state(10, /*with_velocity=*/true);
    state.Reset(T_hat, Matrix6d::Zero(), w_hat, e_w * e_w.transpose());
    state.AddLandmark(LandmarkId(1), p1, Eigen::Matrix3d::Zero(), Eigen::Matrix<double, 3, 6>::Zero());
    state.AddLandmark(LandmarkId(2), p2, Eigen::Matrix3d::Zero(), Eigen::Matrix<double, 3, 6>::Zero());
    state.PredictConstantVelocity(dt, Matrix6d::Zero());

    const Pose T_pred = T_hat * ExpSE3(w_hat * dt);
    EXPECT_TRUE(state.T_w_c().isApprox(T_pred, 1e-12));
    const Pose T_true = T_hat * ExpSE3((w_hat + e_w) * dt);
    const Vector6d xi = LogSE3(T_true * T_pred.inverse());
    Eigen::VectorXd e(18);
    e.head<6>() = xi;
    e.segment<6>(6) = e_w;
    const Eigen::Matrix3d R_phi = ExpSO3(xi.head<3>());
    const Eigen::Matrix3d J_l_inv = LeftJacobianInverseSO3(xi.head<3>());
    e.segment<3>(12) = J_l_inv * (p1 - R_phi * p1);
    e.segment<3>(15) = J_l_inv * (p2 - R_phi * p2);
    const Eigen::MatrixXd expected = e * e.transpose();
    const Eigen::MatrixXd P1 = state.invariant_covariance();
    ASSERT_EQ(P1.rows(), 18);
    EXPECT_LT((P1 - expected).norm(), 1e-3 * expected.norm()) << "component " << k;
  }
}

// Process noise enters the velocity and, through the step, the pose; velocity_covariance() and
// the classic covariance agree.
TEST(EkfStateVelocity, ProcessNoiseAndAccessors) {
  EkfState state(5, /*with_velocity=*/true);
  ASSERT_TRUE(state.has_velocity());
  Vector6d w;
  w << 0, 0, 0.1, 0, 0, 2.0;
  state.Reset(Pose::Identity(), Matrix6d::Identity() * 1e-6, w, Matrix6d::Identity() * 1e-4);
  const Matrix6d Q = Matrix6d::Identity() * 1e-3;
  state.PredictConstantVelocity(0.5, Q);
  EXPECT_LT((state.velocity_covariance() - (1e-4 * Matrix6d::Identity() + Q)).norm(), 1e-12);
  EXPECT_GT(state.pose_covariance()(5, 5), 1e-6 + 0.25 * 1e-4);
  EXPECT_LT((state.covariance().block<6, 6>(6, 6) - state.velocity_covariance()).norm(), 1e-15);
  EXPECT_NEAR(state.T_w_c().translation().z(), 1.0, 1e-3);
  EXPECT_EQ(state.dim(), 12);
}

}  // namespace
}  // namespace dala
