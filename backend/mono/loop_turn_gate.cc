#include "backend/mono/loop_turn_gate.h"

#include <Eigen/Geometry>
#include <cmath>

namespace dala {

LoopTurn CheckLoopTurn(const Pose& T_w_c, const Pose& T_w_c_loop, double path, double max_deg,
                       double max_deg_per_unit) {
  LoopTurn out;
  const Eigen::AngleAxisd turn(T_w_c.rotation().transpose() * T_w_c_loop.rotation());
  out.turn_deg = turn.angle() * 180.0 / M_PI;
  out.max_deg = max_deg + max_deg_per_unit * path;
  out.within = out.turn_deg <= out.max_deg;
  return out;
}

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
