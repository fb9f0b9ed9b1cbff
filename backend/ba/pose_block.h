#ifndef DALA_BACKEND_BA_POSE_BLOCK_H_
#define DALA_BACKEND_BA_POSE_BLOCK_H_

// How backend/ba stores a pose T_w_c in a Ceres parameter block, stated once here.
//
// Block: a 7-vector x = [qx qy qz qw tx ty tz] (Eigen quaternion order, Hamilton), with q the
// rotation R_w_c and t = t_w_c, so p_w = R_w_c * p_c + t_w_c.
// Manifold: ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>.
// Its 6-dof tangent d = [a; dt] acts as
//   Plus(x, d) = ( [cos|a|, sin|a| a/|a|] * q ,  t + dt ),
// i.e. a LEFT (world-frame) rotation by the angle 2|a| about a/|a| (Ceres's quaternion tangent is
// a half angle), and a world-frame translation increment. The marginalisation prior and the
// Jacobians of the linearised system live in this tangent ("manifold tangent").
//
// dala's convention for pose covariances (core/geometry.h) is the right perturbation
// T = T_hat * Exp([phi; rho]). To first order R_hat Exp(phi) = Exp(2a) R_hat and
// t_hat + R_hat rho = t_hat + dt, so [phi; rho] = A * [a; dt] with A = diag(2 R^T, R^T);
// ManifoldToRightPerturbation returns A.

#include <ceres/manifold.h>

#include <array>
#include <memory>

#include "core/geometry.h"

namespace dala {

using PoseBlock = std::array<double, 7>;

PoseBlock PoseToBlock(const Pose& T_w_c);
Pose BlockToPose(const PoseBlock& x);
Pose BlockToPose(const double* x);

// A new ProductManifold<EigenQuaternionManifold, EuclideanManifold<3>> (caller owns it, or hands
// it to a ceres::Problem that takes ownership).
std::unique_ptr<ceres::Manifold> MakePoseManifold();

// Matrix A with [phi; rho] (right perturbation, core convention) = A * d (manifold tangent) at
// the pose T_w_c. Covariances map as Sigma_right = A Sigma_manifold A^T.
Matrix6d ManifoldToRightPerturbation(const Pose& T_w_c);

}  // namespace dala

#endif  // DALA_BACKEND_BA_POSE_BLOCK_H_
