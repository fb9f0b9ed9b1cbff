#include "backend/ba/ba_types.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace dala {

bool StereoIntrinsics::IsValid(std::string* why) const {
  auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (!(fx > 0.0) || !(fy > 0.0)) return fail("fx and fy must be > 0");
  if (!std::isfinite(cx) || !std::isfinite(cy)) return fail("cx and cy must be finite");
  if (!(baseline >= 0.0) || !std::isfinite(baseline))
    return fail("baseline must be >= 0 (0 = mono)");
  return true;
}

std::optional<Eigen::Vector3d> TriangulateStereo(const StereoIntrinsics& K,
                                                 const BaObservation& obs,
                                                 double min_disparity_px) {
  if (!K.is_stereo() || !obs.u_right) return std::nullopt;
  const double disparity = obs.uv.x() - *obs.u_right + K.disparity_offset_px;
  if (!(disparity >= min_disparity_px) || disparity <= 0.0) return std::nullopt;
  const double z = K.fx * K.baseline / disparity;
  return Eigen::Vector3d((obs.uv.x() - K.cx) * z / K.fx, (obs.uv.y() - K.cy) * z / K.fy, z);
}

std::optional<Eigen::Vector3d> TriangulateViews(const StereoIntrinsics& K,
                                                const std::vector<Pose>& T_w_c,
                                                const std::vector<Eigen::Vector2d>& uv,
                                                double min_parallax_deg, double min_depth) {
  const size_t n = std::min(T_w_c.size(), uv.size());
  if (n < 2) return std::nullopt;
  Eigen::MatrixXd A(2 * n, 4);
  std::vector<Eigen::Vector3d> bearings_w;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d f((uv[i].x() - K.cx) / K.fx, (uv[i].y() - K.cy) / K.fy, 1.0);
    const Eigen::Matrix<double, 3, 4> P = T_w_c[i].inverse().matrix().topRows<3>();
    A.row(2 * i) = f.x() * P.row(2) - P.row(0);
    A.row(2 * i + 1) = f.y() * P.row(2) - P.row(1);
    bearings_w.push_back(T_w_c[i].rotation() * f.normalized());
  }
  double max_angle = 0.0;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      max_angle =
          std::max(max_angle, std::acos(std::clamp(bearings_w[i].dot(bearings_w[j]), -1.0, 1.0)));
    }
  }
  if (max_angle < min_parallax_deg * M_PI / 180.0) return std::nullopt;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (std::abs(X[3]) < 1e-12) return std::nullopt;
  const Eigen::Vector3d p = X.head<3>() / X[3];
  for (size_t i = 0; i < n; ++i) {
    if ((T_w_c[i].inverse() * p).z() < min_depth) return std::nullopt;
  }
  return p;
}

}  // namespace dala
