#ifndef DALA_CORE_EVAL_TRAJECTORY_FUSION_H_
#define DALA_CORE_EVAL_TRAJECTORY_FUSION_H_

// Fusing several runs over the same frames into one trajectory (`dala fuse`).
//
// Why: one run's error is part bias and part chance. Runs that differ only in their RANSAC
// draws (SystemOptions::ransac_order_seed) share the bias but not the chance: a different
// inlier set at one frame changes which tracks go on, which landmarks the window maps and how
// the scale of one camera drifts, and the run ends up elsewhere (KITTI 06, one camera, ten
// starts: the standard deviation of log ATE between draws of one start is 0.2). The mean of N
// such runs, each brought into a common frame, keeps the shared part and averages the rest.
//
// Each run lives in its own world frame (and, with one camera, its own unit), so the runs are
// first brought onto a common reference, then averaged per stamp, then aligned again onto that
// mean, a few times (a generalised Procrustes mean):
//   S_k = argmin_S sum_t |m_t - S(p_k,t)|^2   (Umeyama, core/eval/alignment.h; Sim(3) or SE(3)),
//   m_t = mean_k S_k(p_k,t),  R_t = the rotation nearest to sum_k R_S_k R_k,t (chordal mean),
// starting from the first run as the mean. The result is expressed in the first run's world
// (the mean aligned onto it by the same kind of transform), so its first pose is near the
// first run's.
//
// Stamps: poses are paired across runs by equal t_ns (runs of the same dataset give the same
// stamps). A stamp some runs lack (a frame lost or skipped there) takes the mean of those that
// have it. Deterministic: the same runs in the same order give the same result.

#include <string>
#include <vector>

#include "core/eval/alignment.h"
#include "core/trajectory.h"

namespace dala {

struct TrajectoryFusionOptions {
  // How a run is brought onto the mean: kSim3 for one camera (each run has its own unit),
  // kSE3 for a stereo rig (metric runs). kNone: the runs are averaged as they are.
  AlignmentType alignment = AlignmentType::kSim3;
  int iterations = 5;  // Align-then-average rounds.
  // Stamps shared by every run that an alignment needs (>= 3).
  int min_common_stamps = 3;

  bool IsValid(std::string* why) const;
};

struct FusedTrajectory {
  Trajectory trajectory;
  // Per pose of `trajectory`: how many runs had it, and the RMS distance of their aligned
  // positions from the mean (in the first run's unit): the runs' disagreement.
  std::vector<int> runs;
  std::vector<double> spread;
  // Per run: its alignment onto the result.
  std::vector<Sim3Alignment> alignments;
};

// Fuses `runs` (at least one; each with timestamps or all without). Returns false and says why
// when they cannot be fused: no run, an empty run, or fewer than min_common_stamps stamps
// shared between a run and the others (no alignment).
bool FuseTrajectories(const std::vector<Trajectory>& runs, const TrajectoryFusionOptions& options,
                      FusedTrajectory* fused, std::string* why);

}  // namespace dala

#endif  // DALA_CORE_EVAL_TRAJECTORY_FUSION_H_
