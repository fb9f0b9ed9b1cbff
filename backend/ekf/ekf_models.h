#ifndef DALA_BACKEND_EKF_EKF_MODELS_H_
#define DALA_BACKEND_EKF_EKF_MODELS_H_

// Observation and prediction models of the EKFs, with their Jacobians in the error state of
// backend/ekf/ekf_state.h (pose: T_w_c = T_hat Exp([phi; rho]); landmark: p_w additive).
//
// Point in the camera: p_c = T_w_c^-1 p_w. With T = T_hat Exp(delta), to first order
//   p_c = Exp(-delta) p_hat_c = p_hat_c - phi x p_hat_c - rho,
// so d p_c / d [phi; rho] = [[p_c]x, -I] and d p_c / d p_w = R_w_c^T.

#include <Eigen/Core>

#include "core/camera.h"
#include "core/geometry.h"

namespace dala {

// F = d delta_cur / d delta_prev of T_w_cur = T_w_prev * T_prev_cur (= Adj(T_prev_cur^-1)).
Matrix6d PredictionJacobian(const Pose& T_prev_cur);

// p_c and its Jacobians (see the file comment).
Eigen::Vector3d PointInCamera(const Pose& T_w_c, const Eigen::Vector3d& p_w,
                              Eigen::Matrix<double, 3, 6>* d_pc_d_pose = nullptr,
                              Eigen::Matrix3d* d_pc_d_pw = nullptr);

// Stereo observation z = (u, v, d) of p_w from the left camera at T_w_c. False when the point is
// not in front of the camera (outputs then untouched).
bool PredictStereoObservation(const StereoRig& rig, const Pose& T_w_c, const Eigen::Vector3d& p_w,
                              Eigen::Vector3d* uvd,
                              Eigen::Matrix<double, 3, 6>* d_uvd_d_pose = nullptr,
                              Eigen::Matrix3d* d_uvd_d_pw = nullptr);

// Monocular observation z = (u, v) of p_w.
bool PredictMonoObservation(const PinholeCamera& camera, const Pose& T_w_c,
                            const Eigen::Vector3d& p_w, Eigen::Vector2d* uv,
                            Eigen::Matrix<double, 2, 6>* d_uv_d_pose = nullptr,
                            Eigen::Matrix<double, 2, 3>* d_uv_d_pw = nullptr);

// Noise of z = (u, v, d = u - u_right) when u, v, u_right are independent with std sigma_px:
//   Cov = sigma^2 [1 0 1; 0 1 0; 1 0 2]   (the disparity shares the noise of u).
Eigen::Matrix3d StereoObservationCovariance(double sigma_px);

// Unit bearing of a pixel in the camera frame and its Jacobian d b / d uv.
Eigen::Vector3d PixelBearing(const PinholeCamera& camera, const Eigen::Vector2d& uv,
                             Eigen::Matrix<double, 3, 2>* d_b_d_uv = nullptr);

}  // namespace dala

#endif  // DALA_BACKEND_EKF_EKF_MODELS_H_
