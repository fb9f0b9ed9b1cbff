#ifndef DALA_BACKEND_MONO_REFINED_TWO_VIEW_H_
#define DALA_BACKEND_MONO_REFINED_TWO_VIEW_H_

// The two-view motion a monocular map (MonoInitializer) or a bridge (keyframe_bridge.h) starts
// from: InitializeTwoView's reconstruction (backend/mono/two_view.h), refined by the two-view BA
// (backend/mono/two_view_refinement.h), its essential matrix sampled twice.
//
// Why twice: RANSAC keeps the essential matrix with the most correspondences within its
// threshold (2 sigma). When the camera turns sharply while it moves little against the depths,
// a rotation mimics part of a translation, and a long valley of wrong motions keeps almost every
// correspondence within 2 px: the count cannot tell them from the true one, and the two-view BA
// started there stays in the wrong basin. Measured on a rendered car drive in KITTI's geometry
// (`dala synth --preset fast --seed 3 --width 1226 --height 370 --fx 707 --fy 707`, frames 20
// -> 21: 8.7 deg of rotation, a 0.6 m step): RANSAC's refined motion was 72 deg off the truth
// (reprojection cost 42 over 397 points, the truth 7 over 433), and the map it started bent the
// run's first metres (Sim(3) ATE 0.30 m over 100 frames). MAGSAC++ (OpenCV's USAC), which weighs
// every correspondence by its likelihood over noise scales, finds the true basin there.
//
// The choice: when RANSAC's model is an essential matrix, MAGSAC++'s is solved as well (and
// refined only when it is a distinct solution, to be scored). Where both land in one basin
// (directions of travel within kDistinctMotionDeg, MAGSAC++'s unrefined: 0.02-1.6 deg apart
// over 38 pairs, KITTI 06 from ten starts and 28 rendered starts) RANSAC's is kept: their motions
// differ by noise, and taking the other sampler's inliers would only reshuffle which landmarks
// start the map (on KITTI that alone moves a start's ATE by up to 2x: docs/results.md). Where
// they are two solutions:
//   - MAGSAC++'s reconstruction passes the tests and its refined motion has the better epipolar
//     score S_E over every correspondence (EpipolarScore): MAGSAC++'s is kept (`magsac`);
//   - MAGSAC++'s reconstruction is refused (too few points, too little parallax, ...): two
//     motions fit and the data cannot say which, so the pair is refused ("two motions fit: ...")
//     and the initialiser waits for the next frame. Measured: `fast` seed 5 in KITTI's geometry,
//     frames 100 -> 103, 53 correspondences bunched in half the image; RANSAC's motion turned
//     31 deg and moved sideways (truth: 5 deg, forward), its map put the first frame 6.6 m off
//     (ATE 0.68 m over 100 frames); refused, the map starts at frame 105 (0.042 m);
//   - otherwise RANSAC's is kept.

#include <optional>
#include <vector>

#include "backend/mono/two_view.h"
#include "core/camera.h"
#include "core/geometry.h"

namespace dala {

struct RefinedTwoView {
  TwoViewResult two_view;  // The kept sampler's reconstruction (ok, reason, model, parallax).
  Pose T_cur_ref = Pose::Identity();                  // Refined; |t| = 1.
  std::vector<std::optional<Eigen::Vector3d>> p_ref;  // Refined (two_view.p_ref's indices).
  bool magsac = false;  // MAGSAC++'s motion was kept (a different solution, better scored).
};

// Directions of travel further apart than this are two solutions, not one solution's noise.
inline constexpr double kDistinctMotionDeg = 10.0;

// Angle between the directions of travel of two unit-baseline motions T_cur_ref (the current
// camera's centre in the reference camera, -R^T t), degrees.
double TravelAngleDeg(const Pose& a, const Pose& b);

// refine = false: the reconstructions are compared unrefined. Not ok: InitializeTwoView's reason,
// or "two motions fit: ..." (above).
RefinedTwoView SolveRefinedTwoView(const PinholeCamera& camera,
                                   const std::vector<Eigen::Vector2d>& uv_ref,
                                   const std::vector<Eigen::Vector2d>& uv_cur,
                                   const TwoViewOptions& options, bool refine);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_REFINED_TWO_VIEW_H_
