#include "core/eval/ate.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>

namespace dala {

double RotationAngleDeg(const Eigen::Matrix3d& R) {
  // |log(R)| through the quaternion (LogSO3): exact near 0 where acos((tr R - 1) / 2) loses
  // half the digits. Same value as evo's so3_log_angle.
  return LogSO3(R).norm() * 180.0 / M_PI;
}

AteResult ComputeAte(const std::vector<Pose>& T_w_c_gt,
                     const std::vector<Pose>& T_w_c_est_aligned) {
  CHECK_EQ(T_w_c_gt.size(), T_w_c_est_aligned.size()) << "ATE needs paired poses";
  AteResult r;
  r.translation_errors.reserve(T_w_c_gt.size());
  r.rotation_errors_deg.reserve(T_w_c_gt.size());
  for (size_t i = 0; i < T_w_c_gt.size(); ++i) {
    r.translation_errors.push_back(
        (T_w_c_gt[i].translation() - T_w_c_est_aligned[i].translation()).norm());
    r.rotation_errors_deg.push_back(
        RotationAngleDeg(T_w_c_gt[i].linear().transpose() * T_w_c_est_aligned[i].linear()));
  }
  r.translation = ComputeStatistics(r.translation_errors);
  r.rotation_deg = ComputeStatistics(r.rotation_errors_deg);
  return r;
}

}  // namespace dala
