#include "backend/ekf/ekf_models.h"

#include <glog/logging.h>

namespace dala {

Matrix6d PredictionJacobian(const Pose& T_prev_cur) { return AdjointSE3(T_prev_cur.inverse()); }

Eigen::Vector3d PointInCamera(const Pose& T_w_c, const Eigen::Vector3d& p_w,
                              Eigen::Matrix<double, 3, 6>* d_pc_d_pose,
                              Eigen::Matrix3d* d_pc_d_pw) {
  const Eigen::Matrix3d R_c_w = T_w_c.linear().transpose();
  const Eigen::Vector3d p_c = R_c_w * (p_w - T_w_c.translation());
  if (d_pc_d_pose != nullptr) *d_pc_d_pose << Skew(p_c), -Eigen::Matrix3d::Identity();
  if (d_pc_d_pw != nullptr) *d_pc_d_pw = R_c_w;
  return p_c;
}

bool PredictStereoObservation(const StereoRig& rig, const Pose& T_w_c, const Eigen::Vector3d& p_w,
                              Eigen::Vector3d* uvd, Eigen::Matrix<double, 3, 6>* d_uvd_d_pose,
                              Eigen::Matrix3d* d_uvd_d_pw) {
  Eigen::Matrix<double, 3, 6> d_pc_d_pose;
  Eigen::Matrix3d d_pc_d_pw, d_uvd_d_pc;
  const Eigen::Vector3d p_c = PointInCamera(T_w_c, p_w, &d_pc_d_pose, &d_pc_d_pw);
  if (!rig.ProjectStereo(p_c, uvd, &d_uvd_d_pc)) return false;
  if (d_uvd_d_pose != nullptr) *d_uvd_d_pose = d_uvd_d_pc * d_pc_d_pose;
  if (d_uvd_d_pw != nullptr) *d_uvd_d_pw = d_uvd_d_pc * d_pc_d_pw;
  return true;
}

bool PredictMonoObservation(const PinholeCamera& camera, const Pose& T_w_c,
                            const Eigen::Vector3d& p_w, Eigen::Vector2d* uv,
                            Eigen::Matrix<double, 2, 6>* d_uv_d_pose,
                            Eigen::Matrix<double, 2, 3>* d_uv_d_pw) {
  Eigen::Matrix<double, 3, 6> d_pc_d_pose;
  Eigen::Matrix3d d_pc_d_pw;
  Eigen::Matrix<double, 2, 3> d_uv_d_pc;
  const Eigen::Vector3d p_c = PointInCamera(T_w_c, p_w, &d_pc_d_pose, &d_pc_d_pw);
  if (!camera.Project(p_c, uv, &d_uv_d_pc)) return false;
  if (d_uv_d_pose != nullptr) *d_uv_d_pose = d_uv_d_pc * d_pc_d_pose;
  if (d_uv_d_pw != nullptr) *d_uv_d_pw = d_uv_d_pc * d_pc_d_pw;
  return true;
}

Eigen::Matrix3d StereoObservationCovariance(double sigma_px) {
  Eigen::Matrix3d C;
  C << 1, 0, 1, 0, 1, 0, 1, 0, 2;
  return sigma_px * sigma_px * C;
}

Eigen::Vector3d PixelBearing(const PinholeCamera& camera, const Eigen::Vector2d& uv,
                             Eigen::Matrix<double, 3, 2>* d_b_d_uv) {
  CHECK(!camera.HasDistortion()) << "PixelBearing: the EKFs take rectified, undistorted pixels";
  const Eigen::Vector3d ray((uv.x() - camera.cx) / camera.fx, (uv.y() - camera.cy) / camera.fy,
                            1.0);
  const double norm = ray.norm();
  const Eigen::Vector3d b = ray / norm;
  if (d_b_d_uv != nullptr) {
    Eigen::Matrix<double, 3, 2> d_ray_d_uv = Eigen::Matrix<double, 3, 2>::Zero();
    d_ray_d_uv(0, 0) = 1.0 / camera.fx;
    d_ray_d_uv(1, 1) = 1.0 / camera.fy;
    *d_b_d_uv = (Eigen::Matrix3d::Identity() - b * b.transpose()) / norm * d_ray_d_uv;
  }
  return b;
}

}  // namespace dala
