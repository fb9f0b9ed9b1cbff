#include "backend/ba/reprojection_factors.h"

#include <glog/logging.h>

namespace dala {

int ResidualDof(const StereoIntrinsics& K, const BaObservation& obs) {
  return (obs.is_stereo() && K.is_stereo()) ? 3 : 2;
}

ceres::CostFunction* CreateReprojectionCost(const StereoIntrinsics& K, const BaObservation& obs) {
  CHECK_GT(obs.sigma_px, 0.0) << "observation of landmark " << obs.landmark << " has sigma <= 0";
  if (ResidualDof(K, obs) == 3) {
    return StereoReprojectionError::Create(K, obs.uv, *obs.u_right, obs.sigma_px);
  }
  return MonoReprojectionError::Create(K, obs.uv, obs.sigma_px);
}

double WhitenedSquaredError(const StereoIntrinsics& K, const BaObservation& obs, const double* x,
                            const double* p_w, double* depth) {
  double r[3] = {0.0, 0.0, 0.0};
  if (ResidualDof(K, obs) == 3) {
    StereoReprojectionError(K, obs.uv, *obs.u_right, obs.sigma_px)(x, p_w, r);
  } else {
    MonoReprojectionError(K, obs.uv, obs.sigma_px)(x, p_w, r);
  }
  if (depth) *depth = WorldToCamera(x, p_w).z();
  return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

}  // namespace dala
