#ifndef DALA_BACKEND_BA_POSE_ONLY_H_
#define DALA_BACKEND_BA_POSE_ONLY_H_

// Pose-only optimisation of a frame between keyframes: the camera pose T_w_c is refined against
// landmarks held constant (the window's map), with the same reprojection factors and robust loss
// as the window BA. Returns the pose, its 6x6 covariance and a status.
//
// Covariance: Sigma = (J^T J)^-1 at the solution, J the whitened (and IRLS-weighted) Jacobian in
// the manifold tangent, mapped to dala's convention (right perturbation T = T_hat Exp([phi; rho]),
// order [rotation; translation], core/geometry.h) by Sigma_right = A Sigma A^T
// (backend/ba/pose_block.h). It assumes the landmarks exact, so it is optimistic by the map's
// own uncertainty.
//
// Usage:
//   PoseOnlyResult res = EstimatePoseOnly(K, obs, [&](LandmarkId id) { return map.Find(id); },
//                                         T_w_c_predicted, PoseOnlyOptions());
//   if (res.status == PoseOnlyStatus::kOk) use(res.T_w_c, res.covariance);

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "backend/ba/ba_loss.h"
#include "backend/ba/ba_types.h"

namespace dala {

struct PoseOnlyOptions {
  RobustLoss loss = RobustLoss::kHuber;
  // Scale of the loss on the whitened residual norm (pixels / sigma). sqrt(5.991) = 2.45: an
  // inlier at the mono 95% bound is still in the quadratic part.
  double loss_scale = 2.45;
  int max_num_iterations = 10;  // Per solve: the work bound (a solve takes ~3 ms).
  // Per solve; 0 = no time limit (backend/ba/solver_time.h). A positive value is an opt-in
  // budget that makes the result depend on the machine's load.
  double max_solver_time_in_seconds = 0.0;
  // Remove observations above the chi-square 95% quantile after a solve, and re-solve
  // (up to max_outlier_rounds times).
  bool remove_outliers = true;
  int max_outlier_rounds = 2;
  // Fewer inlier observations than this => kTooFewObservations.
  int min_inliers = 6;
  double min_depth = 0.05;  // metres; a point closer (or behind) is an outlier.
  int num_threads = 1;

  bool IsValid(std::string* why) const;
};

enum class PoseOnlyStatus {
  kOk,
  kTooFewObservations,  // not enough observations of known landmarks (before or after outliers).
  kDegenerate,          // the information matrix J^T J is (numerically) singular.
  kSolverFailed,        // Ceres reported a failure (e.g. non-finite values).
};
const char* PoseOnlyStatusName(PoseOnlyStatus s);

struct PoseOnlyResult {
  PoseOnlyStatus status = PoseOnlyStatus::kSolverFailed;
  Pose T_w_c = Pose::Identity();
  Matrix6d covariance = Matrix6d::Zero();  // right perturbation, [rotation; translation].
  std::vector<bool> inliers;               // per input observation.
  int num_inliers = 0;
  int num_outliers_removed = 0;
  int num_iterations = 0;
  double final_cost = 0.0;
};

using LandmarkLookup = std::function<std::optional<Eigen::Vector3d>(LandmarkId)>;

// Observations of landmarks the lookup does not know are ignored (inliers[i] = false).
PoseOnlyResult EstimatePoseOnly(const StereoIntrinsics& K,
                                const std::vector<BaObservation>& observations,
                                const LandmarkLookup& p_w_of, const Pose& T_w_c_guess,
                                const PoseOnlyOptions& options);

}  // namespace dala

#endif  // DALA_BACKEND_BA_POSE_ONLY_H_
