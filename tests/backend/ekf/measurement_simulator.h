#ifndef DALA_TESTS_BACKEND_EKF_MEASUREMENT_SIMULATOR_H_
#define DALA_TESTS_BACKEND_EKF_MEASUREMENT_SIMULATOR_H_

// A FrameMeasurement stream generated from geometric ground truth, for the estimator tests: a
// camera path, random 3D points, noisy projections (uv, u_right with sigma_px), the stereo point
// and its covariance as the frontend gives them, and noisy relative motions consistent with
// their covariance: T_prev_cur_true = T_hat Exp(eta), eta ~ N(0, cov).
// Unlike a real frontend, the motion noise is independent of the observation noise.

#include <Eigen/Core>
#include <cstdint>
#include <set>
#include <vector>

#include "core/camera.h"
#include "core/frame_measurement.h"
#include "core/geometry.h"
#include "core/trajectory.h"

namespace dala::testing {

enum class SimPath {
  kCurve,    // Forward (+z) at `speed` per frame, yaw oscillating, slight pitch/roll.
  kLateral,  // Sideways (+x) at `speed` per frame, no rotation.
  kCircle,   // Circle of `radius`, looking along the tangent, `turns` turns over the frames.
};

struct SimOptions {
  SimPath path = SimPath::kCurve;
  int frames = 150;
  double speed = 0.3;    // m per frame (curve, lateral).
  double radius = 10.0;  // m (circle).
  double turns = 1.0;    // Circle turns over the whole sequence.
  int num_points = 1000;
  // Points are drawn in the view frustum of a random frame, depth in [min, max] (m), unless
  // `points_w` is given.
  double point_min_depth = 2.0;
  double point_max_depth = 30.0;
  std::vector<Eigen::Vector3d> points_w;
  double sigma_px = 0.5;
  bool stereo = true;
  // Per-frame motion noise std (rad, m); motion fills m.motion, and m.odometry too when asked.
  double motion_sigma_rot = 0.002;
  double motion_sigma_trans = 0.01;
  bool fill_odometry = false;
  // Motion estimated from the same noisy stereo points that the frame's observations carry
  // (weighted 3D-3D least squares between the previous and the current frame, covariance
  // (J^T W J)^-1), as a real frontend's visual odometry: its error is then correlated with the
  // observations. motion_sigma_* are ignored (their draws still happen: same random stream).
  bool motion_from_stereo_points = false;
  std::set<int> lost_frames;  // Frames without motion estimate (status kLost).
  // A point unseen for more than one frame gets a new landmark id (as a tracker does), unless
  // persistent_ids (as when loop recognition gives the old ids back).
  bool persistent_ids = false;
  // Loop recognition as the frontend does it (core/frame_measurement.h, LoopDetection): at frame
  // `loop_frame` (if >= 0), every observed point that was seen in the first `loop_old_frames`
  // frames is relabelled with the id it had then, m.loop lists the (current, old) pairs, and the
  // track continues under the old id. Not combined with persistent_ids.
  int loop_frame = -1;
  int loop_old_frames = 10;
  uint32_t seed = 1;
};

struct SimStream {
  StereoRig rig;
  std::vector<Pose> T_w_c_gt;  // T_w_c_gt[0] = identity: the filters' world frame.
  Trajectory gt;
  std::vector<Eigen::Vector3d> points_w;
  std::vector<FrameMeasurement> frames;
  Trajectory dead_reckoning;  // Composition of the noisy motions (identity while lost).
};

// 640 x 480, f = 400 px, baseline 0.5 m.
StereoRig SimRig();
SimStream Simulate(const SimOptions& options);

}  // namespace dala::testing

#endif  // DALA_TESTS_BACKEND_EKF_MEASUREMENT_SIMULATOR_H_
