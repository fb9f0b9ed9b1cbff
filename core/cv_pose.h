#ifndef DALA_CORE_CV_POSE_H_
#define DALA_CORE_CV_POSE_H_

// OpenCV's pose pair (rvec, tvec) of solvePnP / solvePnPRansac / solveP3P as a dala Pose, and
// the seeded RANSAC PnP the estimators share.
// OpenCV maps object (world) points into the camera: p_c = R(rvec) p_o + tvec, so the Pose
// returned is T_c_o (invert it for the camera's pose T_o_c).

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "core/geometry.h"

namespace dala {

// rvec: Rodrigues rotation vector (3x1), tvec: translation (3x1), both CV_64F.
Pose PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec);

// What SeededPnpRansac found: whether OpenCV returned a pose, that pose (T_c_o, as above; the
// identity when none) and how many correspondences it kept.
struct PnpRansacResult {
  bool found = false;
  Pose T_c_o = Pose::Identity();
  int inliers = 0;
};

// OpenCV's EPnP inside RANSAC (200 iterations, confidence 0.999, inlier threshold threshold_px)
// on points p_o of a frame o and their pixels uv in a pinhole camera K, the correspondences
// handed over in the order RansacOrder(n, seed): that order is what seeds OpenCV's draws
// (core/ransac_order.h). p_o and uv are parallel; fewer than 4 points: not found.
PnpRansacResult SeededPnpRansac(const std::vector<Eigen::Vector3d>& p_o,
                                const std::vector<Eigen::Vector2d>& uv, const Eigen::Matrix3d& K,
                                double threshold_px, uint64_t seed);

}  // namespace dala

#endif  // DALA_CORE_CV_POSE_H_
