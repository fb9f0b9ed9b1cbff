#ifndef DALA_FRONTEND_KEYFRAME_POLICY_H_
#define DALA_FRONTEND_KEYFRAME_POLICY_H_

#include <string>

#include "core/geometry.h"

namespace dala {

// When does the current frame become a keyframe? When any of these crosses its threshold,
// measured against the last keyframe:
//  - the fraction of the keyframe's tracked landmarks still tracked drops below
//    `min_tracked_fraction` (the view has changed: new landmarks are needed);
//  - the median image displacement of the landmarks tracked since the keyframe (parallax)
//    exceeds `max_parallax_px` (enough baseline for the monocular estimators);
//  - a stereo camera travelled more than `max_distance_baselines` stereo baselines (the
//    temporal baseline to the keyframe against the rig's own: a distance in the rig's unit, not
//    in metres, so it scales with the rig; 0.5 = 0.2 m on the rendered 0.4 m rig, 0.27 m on
//    KITTI's 0.54 m one, where a car at 10 Hz makes a keyframe of every frame; docs/backend.md,
//    "Keyframes"; `revisit_distance_baselines`, 2.5, while the last keyframe's place is held by
//    an older keyframe: a revisit, whose keyframes the map culls into the older ones), or more
//    than `max_distance_m` metres
//    (an optional cap, off by default), or turned more than `max_rotation_rad`;
//  - `max_frames` frames passed (bounded gap for the backend) AND the view has changed at
//    all: a median parallax of at least `min_parallax_px` or a rotation of at least a tenth of
//    `max_rotation_rad`. A still camera (parallax of the image noise only) adds no keyframe, so
//    its map and memory stay bounded (otherwise 1,000 still frames would add 100 keyframes of
//    ~0.5 MB each).
// A frame never becomes a keyframe while fewer than `min_frames` frames passed.
struct KeyframePolicyOptions {
  double min_tracked_fraction = 0.6;
  double max_parallax_px = 30.0;
  double max_distance_baselines = 0.5;  // stereo only; 0: off.
  // The same while revisiting (the last keyframe's place is held by an older keyframe, which
  // the map keeps instead of it): 0 = max_distance_baselines.
  double revisit_distance_baselines = 2.5;
  double max_distance_m = 0.0;  // 0: off.
  double max_rotation_rad = 0.17;  // ~10 degrees.
  int max_frames = 10;
  double min_parallax_px = 1.0;  // ...for the frame-count criterion (see above).
  int min_frames = 1;
  // One camera: the parallax (for max_parallax_px and min_parallax_px alike) is only the image
  // motion the rotation since the keyframe does not explain (the keyframe's pixel turned by
  // R_cur_kf first: the translation's share). Fewer keyframes through turns; measured, not the
  // default (docs/results.md, "stop 58").
  bool mono_parallax_without_rotation = false;

  bool IsValid(std::string* why) const;
};

struct KeyframeEvidence {
  int frames_since_keyframe = 0;
  double tracked_fraction = 1.0;
  double median_parallax_px = 0.0;
  Pose T_kf_cur = Pose::Identity();  // Current camera in the keyframe's camera (estimated).
  double stereo_baseline_m = 0.0;    // The rig's baseline; 0: one camera (no distance unit).
  bool revisiting = false;  // The last keyframe's place is held by an older keyframe.
};

class KeyframePolicy {
 public:
  explicit KeyframePolicy(const KeyframePolicyOptions& options);
  // True when the current frame should become a keyframe; `reason` names the criterion.
  bool IsKeyframe(const KeyframeEvidence& evidence, const char** reason = nullptr) const;

 private:
  KeyframePolicyOptions options_;
};

}  // namespace dala

#endif  // DALA_FRONTEND_KEYFRAME_POLICY_H_
