#ifndef DALA_BACKEND_BA_REPROJECTION_FACTORS_H_
#define DALA_BACKEND_BA_REPROJECTION_FACTORS_H_

// Reprojection residuals of a world point seen by a (rectified stereo or mono) camera.
//
// Parameters: the pose block x = [q_w_c (x y z w); t_w_c] (backend/ba/pose_block.h) and the
// landmark p_w (3). The point in the left camera is p_c = R_w_c^T (p_w - t_w_c) = (x, y, z), and
//   mono:   r = ( fx x/z + cx - u,  fy y/z + cy - v ) / sigma                       (2 residuals)
//   stereo: r = ( ..mono.., fx (x - b)/z + cx - u_r ) / sigma                       (3 residuals)
// (fx (x - b)/z + cx = u - fx b / z: the right camera sits at +b along x of the left camera).
// Residuals are whitened by the pixel standard deviation sigma, so |r|^2 is chi-square with 2 or
// 3 degrees of freedom for an inlier.
//
// These templates are instantiated in reprojection_factors.cc (and the tests) only; the rest of
// backend/ba uses the non-template factory below, which keeps the autodiff code in one
// translation unit.

#include <ceres/autodiff_cost_function.h>
#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "backend/ba/ba_types.h"

namespace dala {

// p_c = R_w_c^T (p_w - t_w_c) for a pose block x.
template <typename T>
Eigen::Matrix<T, 3, 1> WorldToCamera(const T* x, const T* p_w) {
  const Eigen::Map<const Eigen::Quaternion<T>> q_w_c(x);
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_w_c(x + 4);
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(p_w);
  return q_w_c.conjugate() * (p - t_w_c);
}

struct MonoReprojectionError {
  MonoReprojectionError(const StereoIntrinsics& K, const Eigen::Vector2d& uv, double sigma_px)
      : K_(K), uv_(uv), inv_sigma_(1.0 / sigma_px) {}

  template <typename T>
  bool operator()(const T* x, const T* p_w, T* r) const {
    const Eigen::Matrix<T, 3, 1> p_c = WorldToCamera(x, p_w);
    const T inv_z = T(1.0) / p_c.z();
    r[0] = (T(K_.fx) * p_c.x() * inv_z + T(K_.cx) - T(uv_.x())) * T(inv_sigma_);
    r[1] = (T(K_.fy) * p_c.y() * inv_z + T(K_.cy) - T(uv_.y())) * T(inv_sigma_);
    return true;
  }

  static ceres::CostFunction* Create(const StereoIntrinsics& K, const Eigen::Vector2d& uv,
                                     double sigma_px) {
    return new ceres::AutoDiffCostFunction<MonoReprojectionError, 2, 7, 3>(
        new MonoReprojectionError(K, uv, sigma_px));
  }

 private:
  StereoIntrinsics K_;
  Eigen::Vector2d uv_;
  double inv_sigma_;
};

struct StereoReprojectionError {
  StereoReprojectionError(const StereoIntrinsics& K, const Eigen::Vector2d& uv, double u_right,
                          double sigma_px)
      : K_(K), uv_(uv), u_right_(u_right), inv_sigma_(1.0 / sigma_px) {}

  template <typename T>
  bool operator()(const T* x, const T* p_w, T* r) const {
    const Eigen::Matrix<T, 3, 1> p_c = WorldToCamera(x, p_w);
    const T inv_z = T(1.0) / p_c.z();
    r[0] = (T(K_.fx) * p_c.x() * inv_z + T(K_.cx) - T(uv_.x())) * T(inv_sigma_);
    r[1] = (T(K_.fy) * p_c.y() * inv_z + T(K_.cy) - T(uv_.y())) * T(inv_sigma_);
    r[2] = (T(K_.fx) * (p_c.x() - T(K_.baseline)) * inv_z + T(K_.cx) - T(u_right_)) * T(inv_sigma_);
    return true;
  }

  static ceres::CostFunction* Create(const StereoIntrinsics& K, const Eigen::Vector2d& uv,
                                     double u_right, double sigma_px) {
    return new ceres::AutoDiffCostFunction<StereoReprojectionError, 3, 7, 3>(
        new StereoReprojectionError(K, uv, u_right, sigma_px));
  }

 private:
  StereoIntrinsics K_;
  Eigen::Vector2d uv_;
  double u_right_;
  double inv_sigma_;
};

// The stereo factor when obs has u_right (and K is stereo), else the mono factor. The caller
// owns the result (or hands it to a ceres::Problem).
ceres::CostFunction* CreateReprojectionCost(const StereoIntrinsics& K, const BaObservation& obs);

// Whitened squared residual |r|^2 of obs at (pose block x, p_w) in double precision, and the
// depth z of the point in the camera. Used by the outlier test: compare to the chi-square
// quantile of ResidualDof(K, obs) degrees of freedom.
double WhitenedSquaredError(const StereoIntrinsics& K, const BaObservation& obs, const double* x,
                            const double* p_w, double* depth);
int ResidualDof(const StereoIntrinsics& K, const BaObservation& obs);

}  // namespace dala

#endif  // DALA_BACKEND_BA_REPROJECTION_FACTORS_H_
