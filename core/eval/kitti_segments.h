#ifndef DALA_CORE_EVAL_KITTI_SEGMENTS_H_
#define DALA_CORE_EVAL_KITTI_SEGMENTS_H_

#include <vector>

#include "core/geometry.h"

namespace dala {

// The KITTI odometry benchmark's segment errors (devkit evaluate_odometry.cpp):
//  - d_k: path length of the ground truth from pose 0 to pose k (sum of position steps);
//  - for every first frame f = 0, 10, 20, ... and every length L in {100, 200, ..., 800} m, the
//    last frame l is the first index with d_l > d_f + L (no segment when there is none);
//  - with P ground truth and Q estimate (world <- camera), the segment error is
//      E = (Q_f^-1 Q_l)^-1 (P_f^-1 P_l),
//    t_err = |t(E)| / L (m/m), r_err = acos(clamp(0.5 (tr R(E) - 1), -1, 1)) / L (rad/m);
//  - the sequence scores are the plain averages over all segments, reported as
//    t_err in % (x100) and r_err in deg/100m (x 100 x 180/pi).
// Segment errors compare relative motions, so they are invariant to any rigid transform of
// either whole trajectory: expressing the estimate relative to its first pose (the devkit's
// convention, both start at identity) changes nothing, and no alignment is applied. A scale
// error of the estimate is not removed (as in the devkit).
// The devkit's segment lengths: 100, 200, ..., 800 m.
std::vector<double> KittiDevkitLengths();

struct KittiSegmentOptions {
  int step_frames = 10;                                  // First frames are 0, step, 2 step, ...
  std::vector<double> lengths_m = KittiDevkitLengths();  // Segment lengths, metres.
};

struct KittiSegment {
  size_t first = 0;
  size_t last = 0;
  double length_m = 0.0;
  double t_err = 0.0;            // |t(E)| / L, metres per metre.
  double r_err_rad_per_m = 0.0;  // angle(E) / L.
};

struct KittiLengthError {
  double length_m = 0.0;
  size_t count = 0;
  double t_err_percent = 0.0;
  double r_err_deg_per_100m = 0.0;
};

struct KittiSegmentResult {
  std::vector<KittiSegment> segments;
  std::vector<KittiLengthError> per_length;  // Only lengths with at least one segment.
  double t_err_percent = 0.0;                // 100 * mean(t_err).
  double r_err_deg_per_100m = 0.0;           // 100 * 180/pi * mean(r_err).
};

// Computes the segment errors of paired poses (same length, CHECKed). Returns false when the
// trajectory is too short for a single segment of the shortest length.
bool ComputeKittiSegmentErrors(const std::vector<Pose>& T_w_c_gt,
                               const std::vector<Pose>& T_w_c_est,
                               const KittiSegmentOptions& options, KittiSegmentResult* result);

// The devkit's rotation error of an (almost) rotation matrix: acos of 0.5 (tr R - 1) clamped to
// [-1, 1], in radians.
double KittiRotationError(const Eigen::Matrix3d& R);

}  // namespace dala

#endif  // DALA_CORE_EVAL_KITTI_SEGMENTS_H_
