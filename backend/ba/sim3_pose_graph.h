#ifndef DALA_BACKEND_BA_SIM3_POSE_GRAPH_H_
#define DALA_BACKEND_BA_SIM3_POSE_GRAPH_H_

// Sim(3) pose graph over keyframes: the monocular loop closure, where the scale drifts along
// the path and a loop must correct it as well as the pose (Strasdat et al., "Scale drift-aware
// large scale monocular SLAM", RSS 2010; ORB-SLAM's essential graph does the same).
//
// A node S_w_k = (R, t, s) maps keyframe k's camera coordinates to the world:
//   p_w = s R p_k + t.
// s = 1 for every keyframe before the solve (the window's estimate, in the map's unit); after it,
// s_k says how much keyframe k's neighbourhood must grow to agree with the loop. Composition and
// inverse:  S_1 S_2 = (R_1 R_2, s_1 R_1 t_2 + t_1, s_1 s_2),  S^-1 = (R^T, -R^T t / s, 1 / s).
//
// Edge residual for a measurement S_a_b_meas between keyframes a and b:
//   S_err = S_a_b_meas^-1 * (S_w_a^-1 * S_w_b),   e = [2 vec(q_err); t_err; log s_err]   (7)
//   r = sqrt_info * e,   sqrt_info^T sqrt_info = information (7x7, [rotation; translation; log
//   scale]). Block: [qx qy qz qw tx ty tz log s], manifold EigenQuaternion x Euclidean<4>.
// The gauge: the first keyframe (smallest id), pose and scale, is constant. Solver options and
// summary are the SE(3) graph's (backend/ba/pose_graph.h).

#include <map>
#include <vector>

#include "backend/ba/pose_graph.h"
#include "core/geometry.h"
#include "core/types.h"

namespace dala {

using Matrix7d = Eigen::Matrix<double, 7, 7>;

struct Sim3 {
  Pose T = Pose::Identity();  // R and t.
  double scale = 1.0;         // s > 0.

  Sim3 Inverse() const;
  Sim3 operator*(const Sim3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return scale * (T.linear() * p) +
                                                                     T.translation(); }
};

struct Sim3Edge {
  KeyframeId from;                              // a
  KeyframeId to;                                // b
  Sim3 S_from_to;                               // measured S_a_b.
  Matrix7d information = Matrix7d::Identity();  // [rotation; translation; log scale], SPD.
  bool is_loop = false;                         // informational (reports).
};

// Optimises the nodes; edges referring to unknown keyframes are a broken invariant (CHECK).
// Returns the corrected nodes (unchanged if the solve fails, and summary->usable = false).
std::map<KeyframeId, Sim3> OptimizeSim3PoseGraph(const std::map<KeyframeId, Sim3>& S_w_kf,
                                                 const std::vector<Sim3Edge>& edges,
                                                 const PoseGraphOptions& options,
                                                 PoseGraphSummary* summary = nullptr);

}  // namespace dala

#endif  // DALA_BACKEND_BA_SIM3_POSE_GRAPH_H_
