#include "frontend/keyframe_policy.h"

#include <glog/logging.h>

namespace dala {

bool KeyframePolicyOptions::IsValid(std::string* why) const {
  const auto fail = [&](const char* msg) {
    if (why) *why = msg;
    return false;
  };
  if (min_tracked_fraction < 0 || min_tracked_fraction > 1)
    return fail("keyframe.min_tracked_fraction must be in [0, 1]");
  if (max_parallax_px <= 0) return fail("keyframe.max_parallax_px must be > 0");
  if (!(max_distance_m >= 0)) return fail("keyframe.max_distance_m must be >= 0 (0: off)");
  if (!(max_distance_baselines >= 0)) {
    return fail("keyframe.max_distance_baselines must be >= 0 (0: off)");
  }
  if (!(revisit_distance_baselines >= 0)) {
    return fail("keyframe.revisit_distance_baselines must be >= 0 (0: max_distance_baselines)");
  }
  if (max_rotation_rad <= 0) return fail("keyframe.max_rotation_rad must be > 0");
  if (!(min_parallax_px >= 0)) return fail("keyframe.min_parallax_px must be >= 0");
  if (min_frames < 1 || max_frames < min_frames)
    return fail("keyframe: need 1 <= min_frames <= max_frames");
  return true;
}

KeyframePolicy::KeyframePolicy(const KeyframePolicyOptions& options) : options_(options) {
  std::string why;
  CHECK(options_.IsValid(&why)) << why;
}

bool KeyframePolicy::IsKeyframe(const KeyframeEvidence& e, const char** reason) const {
  const auto yes = [&](const char* why) {
    if (reason) *reason = why;
    return true;
  };
  if (e.frames_since_keyframe < options_.min_frames) return false;
  if (e.tracked_fraction < options_.min_tracked_fraction) return yes("tracked fraction");
  if (e.median_parallax_px > options_.max_parallax_px) return yes("parallax");
  const double distance = e.T_kf_cur.translation().norm();
  const double baselines = e.revisiting && options_.revisit_distance_baselines > 0
                               ? options_.revisit_distance_baselines
                               : options_.max_distance_baselines;
  if (baselines > 0 && e.stereo_baseline_m > 0 && distance > baselines * e.stereo_baseline_m) {
    return yes("distance");
  }
  if (options_.max_distance_m > 0 && distance > options_.max_distance_m) return yes("distance");
  if (LogSO3(e.T_kf_cur.linear()).norm() > options_.max_rotation_rad) return yes("rotation");
  const bool moved = e.median_parallax_px >= options_.min_parallax_px ||
                     LogSO3(e.T_kf_cur.linear()).norm() >= 0.1 * options_.max_rotation_rad;
  if (e.frames_since_keyframe >= options_.max_frames && moved) return yes("frame count");
  return false;
}

}  // namespace dala
