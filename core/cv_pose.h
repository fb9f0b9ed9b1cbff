#ifndef DALA_CORE_CV_POSE_H_
#define DALA_CORE_CV_POSE_H_

// OpenCV's pose pair (rvec, tvec) of solvePnP / solvePnPRansac / solveP3P as a dala Pose.
// OpenCV maps object (world) points into the camera: p_c = R(rvec) p_o + tvec, so the Pose
// returned is T_c_o (invert it for the camera's pose T_o_c).

#include <opencv2/core.hpp>

#include "core/geometry.h"

namespace dala {

// rvec: Rodrigues rotation vector (3x1), tvec: translation (3x1), both CV_64F.
Pose PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec);

}  // namespace dala

#endif  // DALA_CORE_CV_POSE_H_
