#include "core/geometry.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/test_util.h"

namespace dala {
namespace {

constexpr double kEps = 1e-6;

class GeometryTest : public ::testing::Test {
 protected:
  std::mt19937 rng_{42};
  Eigen::Vector3d RandomVector(double scale) {
    std::normal_distribution<double> n(0.0, scale);
    return Eigen::Vector3d(n(rng_), n(rng_), n(rng_));
  }
  Vector6d RandomTangent(double rot, double trans) {
    Vector6d xi;
    xi << RandomVector(rot), RandomVector(trans);
    return xi;
  }
};

TEST_F(GeometryTest, SkewIsCrossProduct) {
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d a = RandomVector(3), b = RandomVector(3);
    EXPECT_LT((Skew(a) * b - a.cross(b)).norm(), 1e-12);
  }
}

TEST_F(GeometryTest, SO3ExpLogRoundTrip) {
  for (double scale : {1e-9, 1e-6, 1e-3, 0.5, 1.5}) {
    for (int i = 0; i < 50; ++i) {
      Eigen::Vector3d phi = RandomVector(scale);
      if (phi.norm() > 3.1) phi *= 3.1 / phi.norm();
      const Eigen::Vector3d back = LogSO3(ExpSO3(phi));
      EXPECT_LT((back - phi).norm(), 1e-9 * std::max(1.0, phi.norm())) << phi.transpose();
      EXPECT_LT((ExpSO3(phi).transpose() * ExpSO3(phi) - Eigen::Matrix3d::Identity()).norm(),
                1e-12);
    }
  }
}

TEST_F(GeometryTest, SO3LogNearPi) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3).normalized();
  const double angle = M_PI - 1e-7;
  const Eigen::Vector3d phi = LogSO3(ExpSO3(axis * angle));
  EXPECT_NEAR(phi.norm(), angle, 1e-6);
  EXPECT_LT((phi.normalized() - axis).norm(), 1e-6);
}

TEST_F(GeometryTest, SO3MatchesEigenAngleAxis) {
  const Eigen::Vector3d phi(0.3, -0.2, 0.9);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
  EXPECT_LT((ExpSO3(phi) - R).norm(), 1e-12);
}

// Exp(phi + d) ~= Exp(phi) Exp(Jr(phi) d): compare columns with central differences.
TEST_F(GeometryTest, SO3RightJacobianMatchesNumeric) {
  for (double scale : {1e-7, 0.1, 1.0}) {
    for (int i = 0; i < 20; ++i) {
      const Eigen::Vector3d phi = RandomVector(scale);
      Eigen::Matrix3d numeric;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d d = Eigen::Vector3d::Unit(k) * kEps;
        const Eigen::Matrix3d Rp = ExpSO3(phi).transpose() * ExpSO3(phi + d);
        const Eigen::Matrix3d Rm = ExpSO3(phi).transpose() * ExpSO3(phi - d);
        numeric.col(k) = (LogSO3(Rp) - LogSO3(Rm)) / (2 * kEps);
      }
      EXPECT_LT((RightJacobianSO3(phi) - numeric).norm(), 1e-7) << phi.transpose();
      EXPECT_LT((RightJacobianSO3(phi) * RightJacobianInverseSO3(phi) -
                 Eigen::Matrix3d::Identity()).norm(), 1e-9);
      EXPECT_LT((LeftJacobianSO3(phi) - ExpSO3(phi) * RightJacobianSO3(phi)).norm(), 1e-9);
      EXPECT_LT((LeftJacobianSO3(phi) * LeftJacobianInverseSO3(phi) -
                 Eigen::Matrix3d::Identity()).norm(), 1e-9);
    }
  }
}

TEST_F(GeometryTest, SE3ExpLogRoundTrip) {
  for (double scale : {1e-8, 1e-3, 0.7}) {
    for (int i = 0; i < 50; ++i) {
      const Vector6d xi = RandomTangent(scale, 3.0 * scale + 1e-9);
      EXPECT_LT((LogSE3(ExpSE3(xi)) - xi).norm(), 1e-9 * std::max(1.0, xi.norm()));
    }
  }
}

TEST_F(GeometryTest, SE3ExpIsMatrixExponential) {
  // exp of the 4x4 twist matrix by a long Taylor series, against the closed form.
  const Vector6d xi = (Vector6d() << 0.4, -0.3, 0.8, 1.0, -2.0, 0.5).finished();
  Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
  X.topLeftCorner<3, 3>() = Skew(xi.head<3>());
  X.topRightCorner<3, 1>() = xi.tail<3>();
  Eigen::Matrix4d E = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
  for (int k = 1; k < 40; ++k) {
    term = term * X / k;
    E += term;
  }
  EXPECT_LT((ExpSE3(xi).matrix() - E).norm(), 1e-12);
}

TEST_F(GeometryTest, SE3AdjointMovesPerturbation) {
  for (int i = 0; i < 20; ++i) {
    const Pose T = testing::RandomPose(rng_);
    const Vector6d xi = RandomTangent(0.3, 1.0);
    const Pose lhs = T * ExpSE3(xi);
    const Pose rhs = ExpSE3(AdjointSE3(T) * xi) * T;
    EXPECT_POSE_NEAR(lhs, rhs, 1e-9);
  }
}

TEST_F(GeometryTest, SE3RightJacobianMatchesNumeric) {
  for (double scale : {1e-6, 0.2, 1.0}) {
    for (int i = 0; i < 20; ++i) {
      const Vector6d xi = RandomTangent(scale, 2.0);
      Matrix6d numeric;
      for (int k = 0; k < 6; ++k) {
        const Vector6d d = Vector6d::Unit(k) * kEps;
        const Vector6d p = LogSE3(ExpSE3(xi).inverse() * ExpSE3(xi + d));
        const Vector6d m = LogSE3(ExpSE3(xi).inverse() * ExpSE3(xi - d));
        numeric.col(k) = (p - m) / (2 * kEps);
      }
      EXPECT_LT((RightJacobianSE3(xi) - numeric).norm(), 1e-6) << xi.transpose();
      EXPECT_LT((RightJacobianSE3(xi) * RightJacobianInverseSE3(xi) - Matrix6d::Identity()).norm(),
                1e-9);
    }
  }
}

TEST_F(GeometryTest, InterpolatePoseEndsAndMiddle) {
  const Pose T0 = MakePose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  const Pose T1 = MakePose(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())),
                           Eigen::Vector3d(2, 4, 6));
  EXPECT_POSE_NEAR(InterpolatePose(T0, T1, 0.0), T0, 1e-12);
  EXPECT_POSE_NEAR(InterpolatePose(T0, T1, 1.0), T1, 1e-12);
  const Pose mid = InterpolatePose(T0, T1, 0.5);
  EXPECT_LT((mid.translation() - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_NEAR(LogSO3(mid.linear()).z(), 0.5, 1e-12);
}

TEST_F(GeometryTest, OrthonormalizedFixesDrift) {
  Pose T = testing::RandomPose(rng_);
  T.linear() *= 1.001;
  const Pose F = Orthonormalized(T);
  EXPECT_LT((F.linear().transpose() * F.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

// R (I + S) with S symmetric (a rounded diagonal, as in a 7-digit KITTI file) has the polar factor
// R exactly; a quaternion round trip (Orthonormalized) moves the angle by ~|S|.
TEST_F(GeometryTest, NearestRotationUndoesASymmetricPerturbation) {
  for (int i = 0; i < 20; ++i) {
    const Eigen::Matrix3d R = testing::RandomPose(rng_).linear();
    const Eigen::Vector3d d = RandomVector(3e-7);
    Eigen::Matrix3d S = d.asDiagonal();
    S(0, 1) = S(1, 0) = 1e-7;
    const Eigen::Matrix3d M = R * (Eigen::Matrix3d::Identity() + S);
    const Eigen::Matrix3d N = NearestRotation(M);
    EXPECT_LT((N.transpose() * N - Eigen::Matrix3d::Identity()).norm(), 1e-14);
    EXPECT_NEAR(N.determinant(), 1.0, 1e-14);
    EXPECT_LT(LogSO3(R.transpose() * N).norm(), 1e-14);
    // The quaternion path is off by the size of the perturbation.
    EXPECT_GT(LogSO3(R.transpose() * Orthonormalized(MakePose(M, Eigen::Vector3d::Zero())).linear())
                  .norm(),
              1e-9);
  }
  // A reflection-like input still gives a proper rotation.
  EXPECT_NEAR(NearestRotation(Eigen::Vector3d(1, 1, -1).asDiagonal()).determinant(), 1.0, 1e-14);
}

}  // namespace
}  // namespace dala
