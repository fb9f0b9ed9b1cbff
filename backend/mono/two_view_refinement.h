#ifndef DALA_BACKEND_MONO_TWO_VIEW_REFINEMENT_H_
#define DALA_BACKEND_MONO_TWO_VIEW_REFINEMENT_H_

// Bundle adjustment of a two-view reconstruction (the last step of the monocular
// initialisation, as ORB-SLAM's global BA after its initialiser): the current camera's pose and
// the points minimise the mono reprojection errors in both views (backend/ba/
// reprojection_factors.h, Huber loss), with the 7-dof gauge of one camera fixed as follows:
//   - the reference camera is the world (T_w_ref = I, held constant): 6 dof;
//   - the current camera's position t_w_cur stays on the unit sphere (|t| = 1, the map's unit
//     is the first baseline): 1 dof. Its pose block [q; t] lives on
//     ProductManifold<EigenQuaternionManifold, SphereManifold<3>> (tangent 3 + 2).
// Afterwards a point that is behind either camera or whose whitened squared error exceeds the
// chi-square 95 % bound (2 dof) in either view is dropped (set to nullopt).

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/geometry.h"

namespace dala {

struct TwoViewRefinementSummary {
  bool usable = false;
  double initial_cost = 0.0, final_cost = 0.0;
  int num_points = 0;   // Optimised.
  int num_dropped = 0;  // Removed by the final check.
};

// p_ref[i] (reference camera = world) is the point of uv_ref[i] <-> uv_cur[i] (nullopt: none).
// T_cur_ref must have a unit translation. On failure (Ceres unusable) nothing is changed.
TwoViewRefinementSummary RefineTwoView(const PinholeCamera& camera,
                                       const std::vector<Eigen::Vector2d>& uv_ref,
                                       const std::vector<Eigen::Vector2d>& uv_cur,
                                       double sigma_px, int max_iterations, Pose* T_cur_ref,
                                       std::vector<std::optional<Eigen::Vector3d>>* p_ref);

}  // namespace dala

#endif  // DALA_BACKEND_MONO_TWO_VIEW_REFINEMENT_H_
