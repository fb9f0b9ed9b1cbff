#ifndef DALA_BACKEND_BA_POSE_GRAPH_H_
#define DALA_BACKEND_BA_POSE_GRAPH_H_

// SE(3) pose graph over keyframe poses: relative-pose edges between consecutive keyframes
// (odometry, e.g. from the window BA) and loop-closure edges, solved with Ceres.
//
// Edge residual for a measurement T_a_b_meas between keyframes a and b: backend/ba/
// relative_pose_cost.h (the right-perturbation error in the frame b, whitened by the edge's
// information, dala's convention of core/geometry.h). Poses live on the product manifold of
// backend/ba/pose_block.h. The gauge: the pose of the first keyframe (smallest id) is constant.
//
// The caller moves each landmark with its anchor keyframe after the correction:
//   p_w_new = T_w_a_new * T_w_a_old^-1 * p_w_old.

#include <map>
#include <string>
#include <vector>

#include "backend/ba/ba_loss.h"
#include "core/geometry.h"
#include "core/types.h"

namespace ceres {
class Problem;
}  // namespace ceres

namespace dala {

struct PoseGraphEdge {
  KeyframeId from;                              // a
  KeyframeId to;                                // b
  Pose T_from_to;                               // measured T_a_b.
  Matrix6d information = Matrix6d::Identity();  // [rotation; translation], symmetric PD.
  bool is_loop = false;                         // informational (reports).
};

struct PoseGraphOptions {
  int max_num_iterations = 100;  // The work bound.
  // 0 = no time limit (backend/ba/solver_time.h). A positive value is an opt-in budget that
  // makes the corrected trajectory depend on the machine's load.
  double max_solver_time_in_seconds = 0.0;
  RobustLoss loss = RobustLoss::kNone;  // Huber/Cauchy on the whitened edge error if wanted.
  double loss_scale = 3.5;              // on |r|; sqrt(chi2_6 95%) = 3.55.
  int num_threads = 1;

  bool IsValid(std::string* why) const;
};

struct PoseGraphSummary {
  bool usable = false;
  int num_iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double time_s = 0.0;
};

// Optimises the poses; edges referring to unknown keyframes are a broken invariant (CHECK).
// Returns the corrected poses of every keyframe of `T_w_kf` (unchanged if the solve fails, and
// summary->usable = false).
std::map<KeyframeId, Pose> OptimizePoseGraph(const std::map<KeyframeId, Pose>& T_w_kf,
                                             const std::vector<PoseGraphEdge>& edges,
                                             const PoseGraphOptions& options,
                                             PoseGraphSummary* summary = nullptr);

// Solves a built pose-graph problem (SE(3) or Sim(3)) with `options` and fills `summary`
// (usable, iterations, costs, wall time of the solve). Shared by the two graphs.
void SolvePoseGraphProblem(const PoseGraphOptions& options, ceres::Problem* problem,
                           PoseGraphSummary* summary);

}  // namespace dala

#endif  // DALA_BACKEND_BA_POSE_GRAPH_H_
