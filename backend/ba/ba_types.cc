#include "backend/ba/ba_types.h"

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

}  // namespace dala
