#include "core/geometry.h"

#include <Eigen/SVD>

#include <cmath>

namespace dala {
namespace {
// Below this angle the closed forms are replaced by their Taylor series (to second order, which
// keeps them exact to double precision at these angles).
constexpr double kSmallAngle = 1e-5;
}  // namespace

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  const Eigen::Matrix3d K = Skew(phi);
  if (theta < kSmallAngle) return Eigen::Matrix3d::Identity() + K + 0.5 * K * K;
  return Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  // Through the quaternion: stable near 0 and near pi, unlike acos((tr R - 1)/2).
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2.0 * v;  // theta ~ 2 s for tiny angles.
  const double theta = 2.0 * std::atan2(s, q.w());
  return v * (theta / s);
}

Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& phi) {
  // Jl = I + (1 - cos t)/t^2 K + (t - sin t)/t^3 K^2, K = [phi]x.
  const double t = phi.norm();
  const Eigen::Matrix3d K = Skew(phi);
  if (t < kSmallAngle) return Eigen::Matrix3d::Identity() + 0.5 * K + K * K / 6.0;
  const double t2 = t * t;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(t)) / t2 * K +
         (t - std::sin(t)) / (t2 * t) * K * K;
}

Eigen::Matrix3d LeftJacobianInverseSO3(const Eigen::Vector3d& phi) {
  // Jl^-1 = I - K/2 + (1/t^2 - (1 + cos t)/(2 t sin t)) K^2.
  const double t = phi.norm();
  const Eigen::Matrix3d K = Skew(phi);
  if (t < kSmallAngle) return Eigen::Matrix3d::Identity() - 0.5 * K + K * K / 12.0;
  const double c = 1.0 / (t * t) - (1.0 + std::cos(t)) / (2.0 * t * std::sin(t));
  return Eigen::Matrix3d::Identity() - 0.5 * K + c * K * K;
}

Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi) { return LeftJacobianSO3(-phi); }

Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& phi) {
  return LeftJacobianInverseSO3(-phi);
}

Pose ExpSE3(const Vector6d& xi) {
  const Eigen::Vector3d phi = xi.head<3>();
  const Eigen::Vector3d rho = xi.tail<3>();
  Pose T = Pose::Identity();
  T.linear() = ExpSO3(phi);
  T.translation() = LeftJacobianSO3(phi) * rho;
  return T;
}

Vector6d LogSE3(const Pose& T) {
  Vector6d xi;
  const Eigen::Vector3d phi = LogSO3(T.linear());
  xi.head<3>() = phi;
  xi.tail<3>() = LeftJacobianInverseSO3(phi) * T.translation();
  return xi;
}

Matrix6d AdjointSE3(const Pose& T) {
  Matrix6d A = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  A.topLeftCorner<3, 3>() = R;
  A.bottomLeftCorner<3, 3>() = Skew(T.translation()) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

namespace {
// The Q block of the SE(3) left Jacobian (Barfoot, "State Estimation for Robotics", eq. 7.86),
// written for the [rho; phi] ordering there; we only reorder the blocks around it.
Eigen::Matrix3d SE3QBlock(const Eigen::Vector3d& rho, const Eigen::Vector3d& phi) {
  const double t = phi.norm();
  const Eigen::Matrix3d P = Skew(phi);
  const Eigen::Matrix3d Rh = Skew(rho);
  double a, b, c;
  if (t < 1e-4) {
    a = 1.0 / 6.0;
    b = 1.0 / 24.0;
    c = 1.0 / 120.0;
  } else {
    const double t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
    const double s = std::sin(t), co = std::cos(t);
    a = (t - s) / t3;
    b = (t2 + 2.0 * co - 2.0) / (2.0 * t4);
    c = (2.0 * t - 3.0 * s + t * co) / (2.0 * t5);
  }
  return 0.5 * Rh + a * (P * Rh + Rh * P + P * Rh * P) +
         b * (P * P * Rh + Rh * P * P - 3.0 * P * Rh * P) +
         c * (P * Rh * P * P + P * P * Rh * P);
}

Matrix6d LeftJacobianSE3(const Vector6d& xi) {
  const Eigen::Vector3d phi = xi.head<3>();
  const Eigen::Vector3d rho = xi.tail<3>();
  const Eigen::Matrix3d Jl = LeftJacobianSO3(phi);
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = Jl;
  J.bottomRightCorner<3, 3>() = Jl;
  J.bottomLeftCorner<3, 3>() = SE3QBlock(rho, phi);
  return J;
}
}  // namespace

Matrix6d RightJacobianSE3(const Vector6d& xi) { return LeftJacobianSE3(-xi); }

Matrix6d RightJacobianInverseSE3(const Vector6d& xi) {
  // Block lower-triangular: inv([A 0; Q A]) = [A^-1 0; -A^-1 Q A^-1  A^-1].
  const Matrix6d J = RightJacobianSE3(xi);
  const Eigen::Matrix3d Ainv = J.topLeftCorner<3, 3>().inverse();
  Matrix6d Jinv = Matrix6d::Zero();
  Jinv.topLeftCorner<3, 3>() = Ainv;
  Jinv.bottomRightCorner<3, 3>() = Ainv;
  Jinv.bottomLeftCorner<3, 3>() = -Ainv * J.bottomLeftCorner<3, 3>() * Ainv;
  return Jinv;
}

Pose MakePose(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  Pose T = Pose::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

Pose MakePose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Pose InterpolatePose(const Pose& T0, const Pose& T1, double s) {
  const Eigen::Quaterniond q0(T0.linear()), q1(T1.linear());
  return MakePose(q0.slerp(s, q1), (1.0 - s) * T0.translation() + s * T1.translation());
}

Pose Orthonormalized(const Pose& T) {
  return MakePose(Eigen::Quaterniond(T.linear()).normalized(), T.translation());
}

Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& M) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

}  // namespace dala
