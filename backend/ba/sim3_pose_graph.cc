#include "backend/ba/sim3_pose_graph.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <ceres/problem.h>
#include <glog/logging.h>

#include <array>
#include <cmath>
#include <string>

#include "backend/ba/pose_graph_problem.h"

namespace dala {
namespace {

using Sim3Block = std::array<double, 8>;  // [qx qy qz qw tx ty tz log s]

Sim3Block ToBlock(const Sim3& S) {
  const Eigen::Quaterniond q(S.T.rotation());
  return {q.x(), q.y(), q.z(), q.w(), S.T.translation().x(), S.T.translation().y(),
          S.T.translation().z(), std::log(S.scale)};
}

Sim3 FromBlock(const Sim3Block& x) {
  Sim3 S;
  S.T = MakePose(Eigen::Quaterniond(x[3], x[0], x[1], x[2]).normalized().toRotationMatrix(),
                 Eigen::Vector3d(x[4], x[5], x[6]));
  S.scale = std::exp(x[7]);
  return S;
}

struct RelativeSim3Error {
  RelativeSim3Error(const Sim3& S_a_b_meas, const Matrix7d& sqrt_info)
      : q_meas_inv_(Eigen::Quaterniond(S_a_b_meas.T.rotation()).conjugate()),
        t_meas_(S_a_b_meas.T.translation()),
        log_s_meas_(std::log(S_a_b_meas.scale)),
        sqrt_info_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* x_a, const T* x_b, T* r) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_a(x_a);
    const Eigen::Map<const Vec3> t_w_a(x_a + 4);
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(x_b);
    const Eigen::Map<const Vec3> t_w_b(x_b + 4);
    // Estimated S_a_b = S_w_a^-1 S_w_b = (R_a^T R_b, R_a^T (t_b - t_a) / s_a, s_b / s_a).
    const Eigen::Quaternion<T> q_a_w = q_w_a.conjugate();
    const Eigen::Quaternion<T> q_a_b = q_a_w * q_w_b;
    const Vec3 t_a_b = (q_a_w * (t_w_b - t_w_a)) * exp(-x_a[7]);
    const T log_s_a_b = x_b[7] - x_a[7];
    // S_err = S_meas^-1 S_a_b = (R_m^T R_a_b, R_m^T (t_a_b - t_m) / s_m, s_a_b / s_m).
    const Eigen::Quaternion<T> q_meas_inv = q_meas_inv_.template cast<T>();
    Eigen::Quaternion<T> q_err = q_meas_inv * q_a_b;
    if (q_err.w() < T(0.0)) q_err.coeffs() = -q_err.coeffs();
    const Vec3 t_err =
        (q_meas_inv * (t_a_b - t_meas_.template cast<T>())) * T(std::exp(-log_s_meas_));
    Eigen::Matrix<T, 7, 1> e;
    e << T(2.0) * q_err.vec(), t_err, log_s_a_b - T(log_s_meas_);
    Eigen::Map<Eigen::Matrix<T, 7, 1>> res(r);
    res = sqrt_info_.template cast<T>() * e;
    return true;
  }

  static ceres::CostFunction* Create(const Sim3& S_a_b_meas, const Matrix7d& sqrt_info) {
    return new ceres::AutoDiffCostFunction<RelativeSim3Error, 7, 8, 8>(
        new RelativeSim3Error(S_a_b_meas, sqrt_info));
  }

 private:
  Eigen::Quaterniond q_meas_inv_;
  Eigen::Vector3d t_meas_;
  double log_s_meas_;
  Matrix7d sqrt_info_;
};

}  // namespace

Sim3 Sim3::Inverse() const {
  Sim3 out;
  out.T.linear() = T.linear().transpose();
  out.T.translation() = -(T.linear().transpose() * T.translation()) / scale;
  out.scale = 1.0 / scale;
  return out;
}

Sim3 Sim3::operator*(const Sim3& other) const {
  Sim3 out;
  out.T.linear() = T.linear() * other.T.linear();
  out.T.translation() = scale * (T.linear() * other.T.translation()) + T.translation();
  out.scale = scale * other.scale;
  return out;
}

std::map<KeyframeId, Sim3> OptimizeSim3PoseGraph(const std::map<KeyframeId, Sim3>& S_w_kf,
                                                 const std::vector<Sim3Edge>& edges,
                                                 const PoseGraphOptions& options,
                                                 PoseGraphSummary* summary) {
  std::string why;
  CHECK(options.IsValid(&why)) << "invalid PoseGraphOptions: " << why;
  PoseGraphSummary local;
  PoseGraphSummary& s = summary ? *summary : local;
  s = PoseGraphSummary();
  if (S_w_kf.empty()) return S_w_kf;

  std::map<KeyframeId, Sim3Block> blocks;
  for (const auto& [id, S] : S_w_kf) {
    CHECK_GT(S.scale, 0.0) << "keyframe " << id << ": Sim(3) scale must be > 0";
    blocks[id] = ToBlock(S);
  }
  ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<4>> manifold;
  SolvePoseGraph(&blocks, &manifold, edges, options,
                 [](const Sim3Edge& e, const Matrix7d& sqrt_info) {
                   return RelativeSim3Error::Create(e.S_from_to, sqrt_info);
                 },
                 &s);
  if (!s.usable) return S_w_kf;
  std::map<KeyframeId, Sim3> out;
  for (const auto& [id, x] : blocks) out[id] = FromBlock(x);
  return out;
}

}  // namespace dala
