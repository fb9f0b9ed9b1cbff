#include "backend/ba/reprojection_factors.h"

#include <ceres/manifold.h>
#include <glog/logging.h>

#include <Eigen/Geometry>

#include "core/geometry.h"

namespace dala {

namespace {

// The rows of J_c = dr/dp_c (whitened), see the header.
template <int kRows>
Eigen::Matrix<double, kRows, 3> CameraJacobian(const StereoIntrinsics& K,
                                               const Eigen::Vector3d& p_c, double inv_sigma) {
  const double iz = 1.0 / p_c.z();
  const double a = K.fx * iz * inv_sigma;
  const double b = K.fy * iz * inv_sigma;
  Eigen::Matrix<double, kRows, 3> J;
  J.template topRows<2>() << a, 0.0, -a * p_c.x() * iz,  //
      0.0, b, -b * p_c.y() * iz;
  if constexpr (kRows == 3) J.row(2) << a, 0.0, -a * (p_c.x() - K.baseline) * iz;
  return J;
}

// p_c = R_w_c^T (p_w - t_w_c) for the pose block x; also returns R_w_c and d = p_w - t_w_c.
Eigen::Vector3d PointInCamera(const double* x, const double* p_w, Eigen::Matrix3d* R_w_c,
                              Eigen::Vector3d* d) {
  *R_w_c = Eigen::Quaterniond(x[3], x[0], x[1], x[2]).normalized().toRotationMatrix();
  *d = Eigen::Map<const Eigen::Vector3d>(p_w) - Eigen::Map<const Eigen::Vector3d>(x + 4);
  return R_w_c->transpose() * *d;
}

}  // namespace

template <int kRows>
ReprojectionCost<kRows>::ReprojectionCost(const StereoIntrinsics& K,
                                          const Eigen::Matrix<double, kRows, 1>& uvr_meas,
                                          double sigma_px)
    : K_(K), uvr_meas_(uvr_meas), inv_sigma_(1.0 / sigma_px) {
  CHECK_GT(sigma_px, 0.0);
}

template <int kRows>
bool ReprojectionCost<kRows>::Evaluate(double const* const* parameters, double* residuals,
                                       double** jacobians) const {
  const double* x = parameters[0];
  Eigen::Matrix3d R_w_c;
  Eigen::Vector3d d;
  const Eigen::Vector3d p_c = PointInCamera(x, parameters[1], &R_w_c, &d);
  const double iz = 1.0 / p_c.z();
  Eigen::Map<Eigen::Matrix<double, kRows, 1>> r(residuals);
  r[0] = K_.fx * p_c.x() * iz + K_.cx;
  r[1] = K_.fy * p_c.y() * iz + K_.cy;
  if constexpr (kRows == 3) r[2] = r[0] - K_.fx * K_.baseline * iz + K_.disparity_offset_px;
  r = (r - uvr_meas_) * inv_sigma_;
  if (jacobians == nullptr) return true;

  const Eigen::Matrix<double, kRows, 3> J_w =
      CameraJacobian<kRows>(K_, p_c, inv_sigma_) * R_w_c.transpose();  // dr/dp_w
  if (jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kRows, 7, Eigen::RowMajor>> J_x(jacobians[0]);
    static const ceres::EigenQuaternionManifold kQuaternion;
    Eigen::Matrix<double, 4, 3, Eigen::RowMajor> P;
    kQuaternion.PlusJacobian(x, P.data());
    J_x.template leftCols<4>() = (2.0 * J_w * Skew(d)) * P.transpose();  // (dr/da) P^T
    J_x.template rightCols<3>() = -J_w;
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, kRows, 3, Eigen::RowMajor>> J_p(jacobians[1]);
    J_p = J_w;
  }
  return true;
}

template class ReprojectionCost<2>;
template class ReprojectionCost<3>;

int ResidualDof(const StereoIntrinsics& K, const BaObservation& obs) {
  return (obs.is_stereo() && K.is_stereo()) ? 3 : 2;
}

ceres::CostFunction* CreateReprojectionCost(const StereoIntrinsics& K, const BaObservation& obs) {
  CHECK_GT(obs.sigma_px, 0.0) << "observation of landmark " << obs.landmark << " has sigma <= 0";
  if (ResidualDof(K, obs) == 3) {
    return new ReprojectionCost<3>(K, Eigen::Vector3d(obs.uv.x(), obs.uv.y(), *obs.u_right),
                                   obs.sigma_px);
  }
  return new ReprojectionCost<2>(K, obs.uv, obs.sigma_px);
}

namespace {

class StereoOffsetCost : public ceres::SizedCostFunction<3, 7, 3, 1> {
 public:
  StereoOffsetCost(const StereoIntrinsics& K, const Eigen::Vector3d& uvr, double sigma_px)
      : K_(K), uvr_(uvr), sigma_px_(sigma_px) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    StereoIntrinsics K = K_;
    K.disparity_offset_px = parameters[2][0];
    double* pose_and_point[2] = {jacobians ? jacobians[0] : nullptr,
                                 jacobians ? jacobians[1] : nullptr};
    if (!ReprojectionCost<3>(K, uvr_, sigma_px_)
             .Evaluate(parameters, residuals, jacobians ? pose_and_point : nullptr)) {
      return false;
    }
    if (jacobians && jacobians[2]) {
      jacobians[2][0] = 0.0;
      jacobians[2][1] = 0.0;
      jacobians[2][2] = 1.0 / sigma_px_;
    }
    return true;
  }

 private:
  StereoIntrinsics K_;
  Eigen::Vector3d uvr_;
  double sigma_px_;
};

class OffsetPriorCost : public ceres::SizedCostFunction<1, 1> {
 public:
  explicit OffsetPriorCost(double sigma_px) : inv_sigma_(1.0 / sigma_px) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    residuals[0] = parameters[0][0] * inv_sigma_;
    if (jacobians && jacobians[0]) jacobians[0][0] = inv_sigma_;
    return true;
  }

 private:
  double inv_sigma_;
};

}  // namespace

ceres::CostFunction* CreateStereoOffsetCost(const StereoIntrinsics& K, const BaObservation& obs) {
  CHECK_EQ(ResidualDof(K, obs), 3) << "a disparity offset needs a stereo observation";
  CHECK_GT(obs.sigma_px, 0.0) << "observation of landmark " << obs.landmark << " has sigma <= 0";
  return new StereoOffsetCost(K, Eigen::Vector3d(obs.uv.x(), obs.uv.y(), *obs.u_right),
                              obs.sigma_px);
}

ceres::CostFunction* CreateOffsetPriorCost(double sigma_px) {
  CHECK_GT(sigma_px, 0.0);
  return new OffsetPriorCost(sigma_px);
}

double WhitenedSquaredError(const StereoIntrinsics& K, const BaObservation& obs, const double* x,
                            const double* p_w, double* depth) {
  const double* parameters[2] = {x, p_w};
  double e2 = 0.0;
  if (ResidualDof(K, obs) == 3) {
    Eigen::Vector3d r;
    ReprojectionCost<3>(K, Eigen::Vector3d(obs.uv.x(), obs.uv.y(), *obs.u_right), obs.sigma_px)
        .Evaluate(parameters, r.data(), nullptr);
    e2 = r.squaredNorm();
  } else {
    Eigen::Vector2d r;
    ReprojectionCost<2>(K, obs.uv, obs.sigma_px).Evaluate(parameters, r.data(), nullptr);
    e2 = r.squaredNorm();
  }
  if (depth) {
    Eigen::Matrix3d R_w_c;
    Eigen::Vector3d d;
    *depth = PointInCamera(x, p_w, &R_w_c, &d).z();
  }
  return e2;
}

}  // namespace dala
