#ifndef DALA_CORE_EVAL_ASSOCIATION_H_
#define DALA_CORE_EVAL_ASSOCIATION_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/trajectory.h"

namespace dala {

// One associated pair: an index into the ground truth and one into the estimate.
struct PoseMatch {
  size_t gt = 0;
  size_t est = 0;
};

// Associates by timestamp as the TUM RGB-D tools (associate.py) do: every (gt, est) pair with
// |t_gt - t_est| <= max_diff_ns is a candidate; candidates are taken greedily by increasing time
// difference (ties broken by est then gt index), each pose matched at most once. The result is
// sorted by est index (and so by time). With max_diff below half the sampling period of both
// trajectories this is identical to evo's associate_trajectories (nearest stamp per pose of the
// shorter trajectory); the two can differ only when two poses of one file compete for the same
// pose of the other, where evo reuses it and this takes the closest once.
std::vector<PoseMatch> AssociateByTime(const Trajectory& gt, const Trajectory& est,
                                       int64_t max_diff_ns);

// The two trajectories reduced to their associated pairs, in the order of the estimate.
struct PairedPoses {
  std::vector<PoseMatch> matches;
  std::vector<int64_t> t_ns;    // Stamp of each pair: the estimate's (or its row index for KITTI).
  std::vector<Pose> T_w_c_gt;   // Ground truth pose of the pair, in the ground truth world.
  std::vector<Pose> T_w_c_est;  // Estimated pose of the pair, in the estimate's world.
  bool by_index = false;        // True when paired by row index (KITTI, no timestamps).

  size_t size() const { return matches.size(); }
};

// Pairs the poses of two trajectories: by time (AssociateByTime) when both carry timestamps, by
// row index when neither does (KITTI files; the lengths must then be equal). Returns false and
// says why (lengths, max diff and both time ranges, ...) when there is no pair, the lengths
// differ, or only one trajectory has timestamps.
bool PairTrajectories(const Trajectory& gt, const Trajectory& est, double max_diff_s,
                      PairedPoses* pairs, std::string* why);

}  // namespace dala

#endif  // DALA_CORE_EVAL_ASSOCIATION_H_
