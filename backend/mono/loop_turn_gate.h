#ifndef DALA_BACKEND_MONO_LOOP_TURN_GATE_H_
#define DALA_BACKEND_MONO_LOOP_TURN_GATE_H_

// One camera's loop, before it is closed: how far would it turn the current camera? The place
// recognition verifies a mono loop by its epipolar geometry, and the estimator then places the
// current keyframe in the old neighbourhood (PnP on the old landmarks, or the landmarks'
// similarity). A right loop moves the camera by the drift since the old keyframe, and the
// heading drifts little: one camera observes rotation as well as a rig does. A loop to a
// look-alike place seen from another street turns it by tens of degrees (rendered KITTI 00,
// 1,700 frames: 93 deg, where the right loops turn by under a degree). The gate is the stereo
// rig's (frontend/place_recognition.h, loop.gate_rotation_deg and loop.gate_rotation_deg_per_m)
// with the path in the map's unit, as one camera has no metre: CheckLoopTurn (core/loop_turn.h)
// with the keyframe path below.

#include <map>

#include "core/geometry.h"
#include "core/loop_turn.h"
#include "core/types.h"

namespace dala {

// The length of the keyframe path from keyframe `from` through every later keyframe (in id
// order) to the current camera centre c_w (map units); 0 when `from` is not among them.
double KeyframePathFrom(const std::map<KeyframeId, Pose>& T_w_kf, KeyframeId from,
                        const Eigen::Vector3d& c_w);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_LOOP_TURN_GATE_H_
