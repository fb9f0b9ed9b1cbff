#include "backend/mono/loop_turn_gate.h"

namespace dala {

double KeyframePathFrom(const std::map<KeyframeId, Pose>& T_w_kf, KeyframeId from,
                        const Eigen::Vector3d& c_w) {
  auto it = T_w_kf.find(from);
  if (it == T_w_kf.end()) return 0.0;
  double path = 0.0;
  Eigen::Vector3d previous = it->second.translation();
  for (++it; it != T_w_kf.end(); ++it) {
    path += (it->second.translation() - previous).norm();
    previous = it->second.translation();
  }
  return path + (c_w - previous).norm();
}

}  // namespace dala
