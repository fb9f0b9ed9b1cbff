#ifndef DALA_CORE_LOOP_TURN_H_
#define DALA_CORE_LOOP_TURN_H_

// The orientation bound of a loop closure, shared by the stereo rig's place recognition
// (frontend/place_recognition.h) and one camera's Sim(3) loop closure
// (backend/mono/loop_turn_gate.h): a loop that would turn the camera from R_w_c to R_w_c_loop is
// accepted when
//   angle(R_w_c^T R_w_c_loop) <= max_deg + max_deg_per_unit * path,
// path the distance travelled since the old keyframe (metres with a rig, the map's unit with one
// camera). A right loop undoes a small heading drift; a loop to a look-alike place seen from
// elsewhere turns the camera by tens of degrees.

#include <Eigen/Core>

namespace dala {

struct LoopTurn {
  double turn_deg = 0.0;  // How far the loop would turn the camera.
  double max_deg = 0.0;   // The bound after this path.
  bool within = false;
};

LoopTurn CheckLoopTurn(const Eigen::Matrix3d& R_w_c, const Eigen::Matrix3d& R_w_c_loop,
                       double path, double max_deg, double max_deg_per_unit);

}  // namespace dala

#endif  // DALA_CORE_LOOP_TURN_H_
