#ifndef DALA_BACKEND_BA_REPROJECTION_FACTORS_H_
#define DALA_BACKEND_BA_REPROJECTION_FACTORS_H_

// Reprojection residuals of a world point seen by a rectified stereo (or mono) camera, with
// analytic Jacobians.
//
// Parameters: the pose block x = [q_w_c (x y z w); t_w_c] (backend/ba/pose_block.h) and the
// landmark p_w (3). The point in the left camera is p_c = R_w_c^T (p_w - t_w_c) = (x, y, z), and
//   mono:   r = ( fx x/z + cx - u,  fy y/z + cy - v ) / sigma                       (2 residuals)
//   stereo: r = ( ..mono.., fx (x - b)/z + cx + delta - u_r ) / sigma               (3 residuals)
// with delta the rig's disparity offset (StereoIntrinsics::disparity_offset_px, usually 0).
// (fx (x - b)/z + cx = u - fx b / z: the right camera sits at +b along x of the left camera).
// Residuals are whitened by the pixel standard deviation sigma, so |r|^2 is chi-square with 2 or
// 3 degrees of freedom for an inlier.
//
// Jacobians (analytic; tests/backend/ba checks them with ceres::GradientChecker). With
// d = p_w - t_w_c and J_c = dr/dp_c (rows (1/sigma)[fx/z, 0, -fx x/z^2], [0, fy/z, -fy y/z^2],
// [fx/z, 0, -fx (x - b)/z^2]): dr/dp_w = J_c R^T, dr/dt = -J_c R^T, and for the rotation in
// Ceres's quaternion tangent a (Plus: q <- [sin|a| a/|a|, cos|a|] * q, a left rotation by 2|a|),
// p_c(a) = R^T Exp(-2a) d ~ p_c + 2 R^T [d]x a, so dr/da = 2 J_c R^T [d]x. Ceres multiplies the
// 4 quaternion columns by the manifold's PlusJacobian P (4x3, orthonormal columns at a unit q),
// so they are written as (dr/da) P^T: then (dr/da) P^T P = dr/da.
//
// Measured alternative, not taken: a stereo observation as two 2-row rays (left (u, v), right
// (u_r, v), v weighted 1/sqrt(2)) gives the same cost and lets Ceres use its compiled <2, 3, 6>
// Schur eliminator (3-row blocks mixed with 2-row ones run the dynamic-size one). The linear
// solver got 40 % faster per iteration, but the doubled number of residual blocks cost more in
// evaluation and preprocessing: the window solve went from 70 to 83 ms (ba_benchmark).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "backend/ba/ba_types.h"

namespace dala {

// The mono (kRows = 2) and the stereo (kRows = 3) residual above.
template <int kRows>
class ReprojectionCost : public ceres::SizedCostFunction<kRows, 7, 3> {
 public:
  // uvr_meas: (u, v) or (u, v, u_r).
  ReprojectionCost(const StereoIntrinsics& K, const Eigen::Matrix<double, kRows, 1>& uvr_meas,
                   double sigma_px);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  StereoIntrinsics K_;
  Eigen::Matrix<double, kRows, 1> uvr_meas_;
  double inv_sigma_;
};

// The stereo cost when obs has u_right (and K is stereo), else the mono cost. The caller owns
// the result (or hands it to a ceres::Problem).
ceres::CostFunction* CreateReprojectionCost(const StereoIntrinsics& K, const BaObservation& obs);

// The stereo cost with the rig's disparity offset as a third parameter block (1 value, pixels,
// replacing K.disparity_offset_px): dr/d(offset) = (0, 0, 1 / sigma). CHECKs a stereo obs.
ceres::CostFunction* CreateStereoOffsetCost(const StereoIntrinsics& K, const BaObservation& obs);
// The prior offset / sigma_px on the disparity offset block (1 residual).
ceres::CostFunction* CreateOffsetPriorCost(double sigma_px);

// Whitened squared residual |r|^2 of obs at (pose block x, p_w) in double precision, and the
// depth z of the point in the camera. Used by the outlier test: compare to the chi-square
// quantile of ResidualDof(K, obs) degrees of freedom.
double WhitenedSquaredError(const StereoIntrinsics& K, const BaObservation& obs, const double* x,
                            const double* p_w, double* depth);
int ResidualDof(const StereoIntrinsics& K, const BaObservation& obs);

}  // namespace dala

#endif  // DALA_BACKEND_BA_REPROJECTION_FACTORS_H_
