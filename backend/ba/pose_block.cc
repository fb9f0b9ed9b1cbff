#include "backend/ba/pose_block.h"

#include <ceres/product_manifold.h>

namespace dala {

PoseBlock PoseToBlock(const Pose& T_w_c) {
  Eigen::Quaterniond q(T_w_c.rotation());
  q.normalize();
  const Eigen::Vector3d& t = T_w_c.translation();
  return {q.x(), q.y(), q.z(), q.w(), t.x(), t.y(), t.z()};
}

Pose BlockToPose(const double* x) {
  Eigen::Quaterniond q(x[3], x[0], x[1], x[2]);
  q.normalize();
  return MakePose(q, Eigen::Vector3d(x[4], x[5], x[6]));
}

Pose BlockToPose(const PoseBlock& x) { return BlockToPose(x.data()); }

std::unique_ptr<ceres::Manifold> MakePoseManifold() {
  return std::make_unique<
      ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>>>();
}

Matrix6d ManifoldToRightPerturbation(const Pose& T_w_c) {
  const Eigen::Matrix3d Rt = T_w_c.rotation().transpose();
  Matrix6d A = Matrix6d::Zero();
  A.topLeftCorner<3, 3>() = 2.0 * Rt;
  A.bottomRightCorner<3, 3>() = Rt;
  return A;
}

}  // namespace dala
