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

  // One stereo-like block on pose + landmark. The innovation covariance is the same in any
  // coordinates; the update is compared with P - K S K^T in the invariant coordinates the state
  // stores, with H_xi = H_classic J, J = d(classic error) / d(invariant error) at the prior.
  EkfUpdateBlock b;
  b.residual = Eigen::Vector3d(0.05, -0.03, 0.02);
  b.R = StereoObservationCovariance(0.5);
  b.H_pose = Eigen::Matrix<double, 3, 6>::Random();
  b.landmark = 0;
  b.H_landmark = Eigen::Matrix3d::Random();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 9);
  H.leftCols(6) = b.H_pose;
  H.rightCols(3) = b.H_landmark;
  const Eigen::MatrixXd S = H * P * H.transpose() + b.R;
  EXPECT_LT((S - state.InnovationCovariance(b)).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::Vector3d p_before = state.p_w(0);
  Eigen::MatrixXd J_e = Eigen::MatrixXd::Zero(9, 9);
  J_e.topLeftCorner<6, 6>() = AdjointSE3(T.inverse());
  J_e.block<3, 3>(6, 0) = -Skew(p_before);
  J_e.block<3, 3>(6, 6).setIdentity();
  const Eigen::MatrixXd P_inv = state.invariant_covariance();
  EXPECT_LT((J_e * P_inv * J_e.transpose() - P).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd H_inv = H * J_e;
  const Eigen::MatrixXd K = P_inv * H_inv.transpose() * S.inverse();
  const Eigen::MatrixXd I_KH = Eigen::MatrixXd::Identity(9, 9) - K * H_inv;
  const Eigen::MatrixXd P_joseph = I_KH * P_inv * I_KH.transpose() + K * b.R * K.transpose();
  const Eigen::VectorXd dx = K * b.residual;
  ASSERT_TRUE(state.Update({b}));
  EXPECT_LT((state.invariant_covariance() - P_joseph).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_POSE_NEAR(state.T_w_c(), ExpSE3(dx.head<6>()) * T, 1e-10);
  const Eigen::Vector3d phi = dx.head<3>();
  EXPECT_LT((state.p_w(0) - (ExpSO3(phi) * p_before + LeftJacobianSO3(phi) * dx.tail<3>())).norm(),
            1e-10);
  // To first order this is the classic update T Exp(K_c r), p + K_c r (K_c = P H^T S^-1).
  const Eigen::VectorXd dx_classic = P * H.transpose() * S.ldlt().solve(b.residual);
  EXPECT_LT(LogSE3((T * ExpSE3(dx_classic.head<6>())).inverse() * state.T_w_c()).norm(),
            10 * dx_classic.squaredNorm());

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

// The prediction, seen in the classic coordinates, is the classic one: P_pp <- F P_pp F^T + Q,
// P_pl <- F P_pl, P_ll unchanged (F = Adj(M^-1)).
TEST(EkfStateTest, PredictionEqualsClassicPrediction) {
  EkfState state(3);
  std::mt19937 rng(11);
  const Pose T = testing::RandomPose(rng);
  Matrix6d P0 = Matrix6d::Identity() * 0.02;
  P0(1, 4) = P0(4, 1) = 0.005;
  state.Reset(T, P0);
  state.AddLandmarkFromCamera(LandmarkId(1), Eigen::Vector3d(1, 2, 8), Eigen::Matrix3d::Identity());
  state.AddLandmarkFromCamera(LandmarkId(2), Eigen::Vector3d(-3, 0, 5),
                              0.1 * Eigen::Matrix3d::Identity());
  const Eigen::MatrixXd P = state.covariance();
  const Pose M = testing::RandomPose(rng, 0.3, 1.0);
  Matrix6d Q = Matrix6d::Identity() * 1e-3;
  Q(0, 5) = Q(5, 0) = 2e-4;
  state.Predict(M, Q);
  EXPECT_POSE_NEAR(state.T_w_c(), T * M, 1e-12);
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(12, 12);
  F.topLeftCorner<6, 6>() = PredictionJacobian(M);
  Eigen::MatrixXd expected = F * P * F.transpose();
  expected.topLeftCorner<6, 6>() += Q;
  EXPECT_LT((state.covariance() - expected).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((state.pose_covariance() - expected.topLeftCorner<6, 6>()).cwiseAbs().maxCoeff(),
            1e-10);
  EXPECT_LT((state.landmark_covariance(1) - expected.block<3, 3>(9, 9)).cwiseAbs().maxCoeff(),
            1e-10);
}

// The reason for the invariant error: an observation never adds information along the
// unobservable directions N (global rotation [I; 0; 0..], global translation [0; I; I..]),
// whatever the estimate: N^T (P+^-1 - P^-1) N = N^T H^T R^-1 H N = 0.
TEST(EkfStateTest, UpdatesGainNoInformationOnTheGauge) {
  const StereoRig rig = testing::SimRig();
  EkfState state(4);
  std::mt19937 rng(13);
  state.Reset(testing::RandomPose(rng), Matrix6d::Identity() * 0.01);
  const std::vector<Eigen::Vector3d> p_c = {{1, 0.5, 6}, {-2, 1, 9}, {0.5, -1, 4}};
  for (size_t k = 0; k < p_c.size(); ++k) {
    state.AddLandmarkFromCamera(LandmarkId(k), p_c[k], 0.05 * Eigen::Matrix3d::Identity());
  }
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(state.dim(), 6);
  N.topLeftCorner<3, 3>().setIdentity();
  for (int r = 3; r < state.dim(); r += 3) N.block<3, 3>(r, 3).setIdentity();
  for (int step = 0; step < 5; ++step) {
    // Move, then observe with a residual: the estimate (linearisation point) changes each time.
    state.Predict(testing::RandomPose(rng, 0.05, 0.2), Matrix6d::Identity() * 1e-3);
    const Eigen::MatrixXd info_before = state.invariant_covariance().inverse();
    std::vector<EkfUpdateBlock> blocks;
    for (int i = 0; i < state.num_landmarks(); ++i) {
      EkfUpdateBlock b;
      Eigen::Vector3d uvd;
      Eigen::Matrix<double, 3, 6> H_pose;
      Eigen::Matrix3d H_p;
      ASSERT_TRUE(PredictStereoObservation(rig, state.T_w_c(), state.p_w(i), &uvd, &H_pose, &H_p));
      b.residual = Eigen::Vector3d(1.5, -1.0, 0.3);
      b.R = StereoObservationCovariance(0.5);
      b.H_pose = H_pose;
      b.landmark = i;
      b.H_landmark = H_p;
      blocks.push_back(b);
    }
    ASSERT_TRUE(state.Update(blocks));
    const Eigen::MatrixXd gain = state.invariant_covariance().inverse() - info_before;
    EXPECT_LT((N.transpose() * gain * N).cwiseAbs().maxCoeff(), 1e-6 * gain.cwiseAbs().maxCoeff())
        << "step " << step;
  }
}

}  // namespace
}  // namespace dala
