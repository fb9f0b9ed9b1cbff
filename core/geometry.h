#ifndef DALA_CORE_GEOMETRY_H_
#define DALA_CORE_GEOMETRY_H_

// Lie-group helpers for SO(3) and SE(3), the one copy of them in dala.
//
// Conventions (DESIGN.md), stated once here and used everywhere:
//  - A pose is an Eigen::Isometry3d `T_a_b` that maps a point from frame b to frame a:
//    p_a = T_a_b * p_b. Compose as T_a_c = T_a_b * T_b_c.
//  - Tangent vectors of SE(3) are ordered [rotation; translation] = [phi; rho] (6-vector).
//  - Perturbations are on the right: T = T_hat * Exp(delta). Pose covariances (6x6) are the
//    covariance of that delta, in the same [rotation; translation] order.
//  - SO(3) Exp(phi) = exp([phi]x) (Rodrigues). SE(3) Exp([phi; rho]) = [Exp(phi), J_l(phi) rho; 0 1]
//    (the true group exponential, J_l the left Jacobian of SO(3)).

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace dala {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Pose = Eigen::Isometry3d;

// [v]x, the cross-product matrix: Skew(a) * b = a.cross(b).
Eigen::Matrix3d Skew(const Eigen::Vector3d& v);

// SO(3) exponential (Rodrigues) and logarithm; Log returns phi with |phi| <= pi.
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& phi);
Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R);

// Right Jacobian of SO(3): Exp(phi + dphi) ~= Exp(phi) * Exp(Jr(phi) * dphi).
// Jl(phi) = Jr(-phi) = Exp(phi) * Jr(phi). Inverses are closed form.
Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi);
Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& phi);
Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& phi);
Eigen::Matrix3d LeftJacobianInverseSO3(const Eigen::Vector3d& phi);

// SE(3) exponential and logarithm with tangent [phi; rho].
Pose ExpSE3(const Vector6d& xi);
Vector6d LogSE3(const Pose& T);

// Adjoint of SE(3) for the [rotation; translation] ordering:
// T * Exp(xi) = Exp(Adjoint(T) * xi) * T.  Adj = [R 0; [t]x R  R].
Matrix6d AdjointSE3(const Pose& T);

// Right Jacobian of SE(3) (and its inverse): Exp(xi + dxi) ~= Exp(xi) * Exp(Jr(xi) * dxi).
Matrix6d RightJacobianSE3(const Vector6d& xi);
Matrix6d RightJacobianInverseSE3(const Vector6d& xi);

// Pose from a unit quaternion (Hamilton) and a translation, and back.
Pose MakePose(const Eigen::Quaterniond& q, const Eigen::Vector3d& t);
Pose MakePose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

// Interpolates between two poses for s in [0, 1]: slerp on rotation, linear on translation
// (what the TUM and evo tools do when they resample a trajectory; s outside [0,1] extrapolates).
Pose InterpolatePose(const Pose& T0, const Pose& T1, double s);

// Makes the rotation block of a nearly-orthonormal pose exactly orthonormal (via quaternion).
// Cheap, for poses that drift by repeated products; not the nearest rotation (see below).
Pose Orthonormalized(const Pose& T);

// The rotation nearest to M in the Frobenius norm (orthogonal polar factor, through the SVD;
// det +1). For M = R (I + S) with S symmetric and small it is exactly R, so rounding errors of the
// diagonal of a rotation read from text do not leak into its angle, as they do through a
// quaternion (Orthonormalized shifts the angle by ~|S|, e.g. 1e-7 rad for 7-digit files).
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& M);

}  // namespace dala

#endif  // DALA_CORE_GEOMETRY_H_
