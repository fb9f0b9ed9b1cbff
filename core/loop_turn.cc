#include "core/loop_turn.h"

#include <Eigen/Geometry>
#include <cmath>

namespace dala {

LoopTurn CheckLoopTurn(const Eigen::Matrix3d& R_w_c, const Eigen::Matrix3d& R_w_c_loop,
                       double path, double max_deg, double max_deg_per_unit) {
  LoopTurn out;
  out.turn_deg = Eigen::AngleAxisd(R_w_c.transpose() * R_w_c_loop).angle() * 180.0 / M_PI;
  out.max_deg = max_deg + max_deg_per_unit * path;
  out.within = out.turn_deg <= out.max_deg;
  return out;
}

}  // namespace dala
