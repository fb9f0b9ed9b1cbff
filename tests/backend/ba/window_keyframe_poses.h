#ifndef DALA_TESTS_BACKEND_BA_WINDOW_KEYFRAME_POSES_H_
#define DALA_TESTS_BACKEND_BA_WINDOW_KEYFRAME_POSES_H_

#include <vector>

#include "backend/ba/sliding_window_ba.h"
#include "core/geometry.h"

namespace dala::testing {

// Every keyframe's pose so far, in the order added: those that left the window (their estimate
// when they left), then the window's.
inline std::vector<Pose> AllKeyframePoses(const SlidingWindowBa& ba) {
  std::vector<Pose> out;
  for (const auto& m : ba.marginalized_keyframes()) out.push_back(m.T_w_c);
  for (KeyframeId id : ba.WindowKeyframes()) out.push_back(*ba.KeyframePose(id));
  return out;
}

}  // namespace dala::testing

#endif  // DALA_TESTS_BACKEND_BA_WINDOW_KEYFRAME_POSES_H_
