#ifndef DALA_BACKEND_MONO_KEYFRAME_BRIDGE_H_
#define DALA_BACKEND_MONO_KEYFRAME_BRIDGE_H_

// One camera, a frame that sees too few mapped landmarks to be tracked (a jerk broke the tracks
// and the new ones are not triangulated yet): its pose from the two-view geometry with the last
// keyframe, which has a pose and shares the new tracks.
//
//   T_w_cur = T_w_kf * T_kf_cur,   T_kf_cur = (R, distance * t_dir),
//
// with R and the direction t_dir from SolveRefinedTwoView (backend/mono/refined_two_view.h:
// InitializeTwoView with the caller's tests, the map's first pair's with fewer points, so a weak
// pair is refused, then the two-view BA) on the landmarks both observe, and the distance the
// caller's guess (the last speed times the time since the keyframe: the one thing the pair
// cannot tell). Without it such a frame is lost, the next keyframe cannot be added (a mono
// keyframe needs a pose), the new tracks are never triangulated, and after
// ba.mono_reinit_after_lost_frames a new map starts with its scale and heading guessed across
// the whole gap. Bridged, the scale is guessed across one step and the next keyframe
// triangulates the new tracks with the keyframe; a bridged frame made a keyframe keeps T_kf_cur
// as a prior in the window (BridgeInformation below).

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "backend/ba/ba_types.h"
#include "backend/mono/two_view.h"
#include "core/camera.h"
#include "core/frame_measurement.h"
#include "core/geometry.h"

namespace dala {

struct KeyframeBridge {
  Pose T_w_cur = Pose::Identity();
  int num_points = 0;  // Triangulated by the pair.
  double median_parallax_deg = 0.0;
};

// kf_observations: the keyframe's observations by landmark; m: the current frame. nullopt when
// the pair fails the two-view tests (*why says which) or distance is not positive.
std::optional<KeyframeBridge> BridgeFromKeyframe(
    const PinholeCamera& camera, const Pose& T_w_kf,
    const std::map<LandmarkId, BaObservation>& kf_observations, const FrameMeasurement& m,
    double distance, const TwoViewOptions& options, std::string* why);

// How well a bridge knows T_kf_cur, as the information of a relative-pose prior between the
// keyframe and the bridged frame made a keyframe (SlidingWindowBa::AddRelativePosePrior:
// [rotation; translation], the right perturbation in the current frame). Rotation: 0.01 rad a
// axis (the two-view rotation of >= 20 spread points is good to a fraction of that; the prior
// only has to keep the solve from turning the bridged keyframe with its new landmarks).
// Translation: 0.25 x the step's length, isotropic (the step's length is a guess from the last
// speed, which a jerk changes by tens of percent; the direction is better known, but the prior
// only has to keep the step's scale and place from running away).
Matrix6d BridgeInformation(const Pose& T_kf_cur);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_KEYFRAME_BRIDGE_H_
