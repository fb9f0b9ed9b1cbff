#include "backend/ba/relative_pose_cost.h"

#include <ceres/autodiff_cost_function.h>

namespace dala {
namespace {

struct RelativePoseError {
  RelativePoseError(const Pose& T_a_b_meas, const Matrix6d& sqrt_info)
      : q_b_a_meas_(Eigen::Quaterniond(T_a_b_meas.rotation()).conjugate()),
        t_a_b_meas_(T_a_b_meas.translation()),
        sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* x_a, const T* x_b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_a(x_a);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_w_a(x_a + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(x_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_w_b(x_b + 4);
    // Estimated T_a_b.
    const Eigen::Quaternion<T> q_a_w = q_w_a.conjugate();
    const Eigen::Quaternion<T> q_a_b = q_a_w * q_w_b;
    const Eigen::Matrix<T, 3, 1> t_a_b = q_a_w * (t_w_b - t_w_a);
    // T_err = T_a_b_meas^-1 * T_a_b = [R_meas^T R_a_b, R_meas^T (t_a_b - t_meas)].
    const Eigen::Quaternion<T> q_meas_inv = q_b_a_meas_.template cast<T>();
    Eigen::Quaternion<T> q_err = q_meas_inv * q_a_b;
    if (q_err.w() < T(0.0)) q_err.coeffs() = -q_err.coeffs();
    const Eigen::Matrix<T, 3, 1> t_err = q_meas_inv * (t_a_b - t_a_b_meas_.template cast<T>());
    Eigen::Matrix<T, 6, 1> e;
    e << T(2.0) * q_err.vec(), t_err;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> res(r);
    res = sqrt_info_.template cast<T>() * e;
    return true;
  }

 private:
  Eigen::Quaterniond q_b_a_meas_;
  Eigen::Vector3d t_a_b_meas_;
  Matrix6d sqrt_info_;
};

}  // namespace

ceres::CostFunction* CreateRelativePoseCost(const Pose& T_a_b_meas, const Matrix6d& sqrt_info) {
  return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 7, 7>(
      new RelativePoseError(T_a_b_meas, sqrt_info));
}

}  // namespace dala
