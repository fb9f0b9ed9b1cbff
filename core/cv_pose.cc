#include "core/cv_pose.h"

#include <glog/logging.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "core/ransac_order.h"

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

PnpRansacResult SeededPnpRansac(const std::vector<Eigen::Vector3d>& p_o,
                                const std::vector<Eigen::Vector2d>& uv, const Eigen::Matrix3d& K,
                                double threshold_px, uint64_t seed) {
  CHECK_EQ(p_o.size(), uv.size());
  PnpRansacResult out;
  constexpr size_t kMinPoints = 4;  // OpenCV's own minimum (it throws below it).
  if (p_o.size() < kMinPoints) return out;
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  object.reserve(p_o.size());
  image.reserve(uv.size());
  for (const Eigen::Vector3d& p : p_o) object.emplace_back(p.x(), p.y(), p.z());
  for (const Eigen::Vector2d& q : uv) image.emplace_back(q.x(), q.y());
  cv::Mat K_cv;
  cv::eigen2cv(K, K_cv);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  const std::vector<int> order = RansacOrder(object.size(), seed);
  out.found = cv::solvePnPRansac(Reordered(object, order), Reordered(image, order), K_cv,
                                 cv::noArray(), rvec, tvec, false, 200, threshold_px, 0.999,
                                 inliers, cv::SOLVEPNP_EPNP);
  out.inliers = static_cast<int>(inliers.size());
  if (out.found) out.T_c_o = PoseFromRvecTvec(rvec, tvec);
  return out;
}

}  // namespace dala
