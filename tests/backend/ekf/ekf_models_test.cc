#include "backend/ekf/ekf_models.h"

#include <gtest/gtest.h>

#include <random>

#include "backend/ekf/ekf_state.h"
#include "tests/backend/ekf/measurement_simulator.h"
#include "tests/test_util.h"

namespace dala {
namespace {

constexpr double kEps = 1e-6;

TEST(EkfModelsTest, PredictionJacobianMatchesNumeric) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const Pose T_prev = testing::RandomPose(rng);
    const Pose M = testing::RandomPose(rng, 0.5, 2.0);
    const Matrix6d F = PredictionJacobian(M);
    const Pose T_cur = T_prev * M;
    Matrix6d F_num;
    for (int k = 0; k < 6; ++k) {
      const Vector6d d = Vector6d::Unit(k) * kEps;
      const Pose T_cur_p = T_prev * ExpSE3(d) * M;
      F_num.col(k) = LogSE3(T_cur.inverse() * T_cur_p) / kEps;
    }
    EXPECT_LT((F - F_num).cwiseAbs().maxCoeff(), 1e-5) << F << "\n" << F_num;
  }
}

TEST(EkfModelsTest, StereoAndMonoObservationJacobiansMatchNumeric) {
  const StereoRig rig = testing::SimRig();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 10; ++trial) {
    const Pose T = testing::RandomPose(rng);
    const Eigen::Vector3d p_c(0.5 * trial - 2, 1.0 - 0.2 * trial, 3 + trial);
    const Eigen::Vector3d p_w = T * p_c;
    Eigen::Vector3d z;
    Eigen::Matrix<double, 3, 6> H_pose;
    Eigen::Matrix3d H_p;
    ASSERT_TRUE(PredictStereoObservation(rig, T, p_w, &z, &H_pose, &H_p));
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 6> Hm_pose;
    Eigen::Matrix<double, 2, 3> Hm_p;
    ASSERT_TRUE(PredictMonoObservation(rig.left, T, p_w, &uv, &Hm_pose, &Hm_p));
    EXPECT_LT((uv - z.head<2>()).norm(), 1e-9);
    for (int k = 0; k < 6; ++k) {
      Eigen::Vector3d zp;
      Eigen::Vector2d uvp;
      const Pose Tp = T * ExpSE3(Vector6d::Unit(k) * kEps);
      ASSERT_TRUE(PredictStereoObservation(rig, Tp, p_w, &zp));
      ASSERT_TRUE(PredictMonoObservation(rig.left, Tp, p_w, &uvp));
      EXPECT_LT(((zp - z) / kEps - H_pose.col(k)).norm(), 1e-3 * (1 + H_pose.col(k).norm()));
      EXPECT_LT(((uvp - uv) / kEps - Hm_pose.col(k)).norm(), 1e-3 * (1 + Hm_pose.col(k).norm()));
    }
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d zp;
      Eigen::Vector2d uvp;
      const Eigen::Vector3d pp = p_w + Eigen::Vector3d::Unit(k) * kEps;
      ASSERT_TRUE(PredictStereoObservation(rig, T, pp, &zp));
      ASSERT_TRUE(PredictMonoObservation(rig.left, T, pp, &uvp));
      EXPECT_LT(((zp - z) / kEps - H_p.col(k)).norm(), 1e-3 * (1 + H_p.col(k).norm()));
      EXPECT_LT(((uvp - uv) / kEps - Hm_p.col(k)).norm(), 1e-3 * (1 + Hm_p.col(k).norm()));
    }
  }
  // Behind the camera: no prediction.
  Eigen::Vector3d z;
  EXPECT_FALSE(PredictStereoObservation(rig, Pose::Identity(), Eigen::Vector3d(0, 0, -1), &z));
}

TEST(EkfModelsTest, PixelBearingJacobianMatchesNumeric) {
  const StereoRig rig = testing::SimRig();
  const Eigen::Vector2d uv(100, 400);
  Eigen::Matrix<double, 3, 2> J;
  const Eigen::Vector3d b = PixelBearing(rig.left, uv, &J);
  EXPECT_NEAR(b.norm(), 1.0, 1e-12);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector3d bp = PixelBearing(rig.left, uv + Eigen::Vector2d::Unit(k) * 1e-4);
    EXPECT_LT(((bp - b) / 1e-4 - J.col(k)).norm(), 1e-6);
  }
}

TEST(EkfModelsTest, StereoNoiseIsThatOfUVAndDisparity) {
  // Monte Carlo of (u, v, u - u_right) with independent noise.
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0, 0.7);
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  const int N = 20000;
  for (int i = 0; i < N; ++i) {
    const double u = n(rng), v = n(rng), ur = n(rng);
    const Eigen::Vector3d z(u, v, u - ur);
    C += z * z.transpose() / N;
  }
  EXPECT_LT((C - StereoObservationCovariance(0.7)).cwiseAbs().maxCoeff(), 0.03);
}

// The state's augmentation Jacobian and the batched update against a dense reference.
TEST(EkfStateTest, AugmentationAndUpdateMatchDenseReference) {
  EkfState state(5);
  std::mt19937 rng(7);
  const Pose T = testing::RandomPose(rng);
  Matrix6d P0 = Matrix6d::Identity() * 0.01;
  P0(0, 3) = P0(3, 0) = 0.003;
  state.Reset(T, P0);
  const Eigen::Vector3d p_c(1, -0.5, 6);
  const Eigen::Matrix3d C = Eigen::Vector3d(0.01, 0.02, 0.3).asDiagonal();
  state.AddLandmarkFromCamera(LandmarkId(4), p_c, C);
  ASSERT_EQ(state.IndexOf(LandmarkId(4)), 0);
  EXPECT_LT((state.p_w(0) - T * p_c).norm(), 1e-12);
  // Numeric d p_w / d delta.
  Eigen::Matrix<double, 3, 6> J;
  for (int k = 0; k < 6; ++k) {
    J.col(k) = ((T * ExpSE3(Vector6d::Unit(k) * kEps)) * p_c - T * p_c) / kEps;
  }
  const Eigen::Matrix3d R = T.linear();
  const Eigen::MatrixXd P = state.covariance();
  EXPECT_LT((P.block<3, 6>(6, 0) - J * P0).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LT((P.block<3, 3>(6, 6) - (J * P0 * J.transpose() + R * C * R.transpose()))
                .cwiseAbs()
                .maxCoeff(),
            1e-6);

  // One stereo-like block on pose + landmark; compare with P - K S K^T, K = P H^T S^-1.
  EkfUpdateBlock b;
  b.residual = Eigen::Vector3d(0.5, -0.3, 0.2);
  b.R = StereoObservationCovariance(0.5);
  b.H_pose = Eigen::Matrix<double, 3, 6>::Random();
  b.landmark = 0;
  b.H_landmark = Eigen::Matrix3d::Random();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 9);
  H.leftCols(6) = b.H_pose;
  H.rightCols(3) = b.H_landmark;
  const Eigen::MatrixXd S = H * P * H.transpose() + b.R;
  EXPECT_LT((S - state.InnovationCovariance(b)).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd K = P * H.transpose() * S.inverse();
  const Eigen::MatrixXd I_KH = Eigen::MatrixXd::Identity(9, 9) - K * H;
  const Eigen::MatrixXd P_joseph = I_KH * P * I_KH.transpose() + K * b.R * K.transpose();
  const Eigen::VectorXd dx = K * b.residual;
  const Eigen::Vector3d p_before = state.p_w(0);
  ASSERT_TRUE(state.Update({b}));
  EXPECT_LT((state.covariance() - P_joseph).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((state.p_w(0) - p_before - dx.tail<3>()).norm(), 1e-10);
  EXPECT_POSE_NEAR(state.T_w_c(), T * ExpSE3(dx.head<6>()), 1e-10);

  // Removing a landmark keeps the others' covariance blocks.
  state.AddLandmarkFromCamera(LandmarkId(9), Eigen::Vector3d(0, 0, 3), C);
  const Eigen::MatrixXd P2 = state.covariance();
  state.RemoveLandmarks({true, false});
  ASSERT_EQ(state.num_landmarks(), 1);
  EXPECT_EQ(state.IndexOf(LandmarkId(9)), 0);
  EXPECT_EQ(state.IndexOf(LandmarkId(4)), -1);
  EXPECT_LT((state.covariance().block<3, 3>(6, 6) - P2.block<3, 3>(9, 9)).cwiseAbs().maxCoeff(),
            1e-15);
  EXPECT_LT((state.covariance().block<6, 3>(0, 6) - P2.block<6, 3>(0, 9)).cwiseAbs().maxCoeff(),
            1e-15);
}

}  // namespace
}  // namespace dala
