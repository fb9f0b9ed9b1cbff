#include "core/cv_pose.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace dala {

Pose PoseFromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R_cv;
  cv::Rodrigues(rvec, R_cv);
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  cv::cv2eigen(R_cv, R);
  cv::cv2eigen(tvec, t);
  return MakePose(R, t);
}

}  // namespace dala
