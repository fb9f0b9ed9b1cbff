#include "backend/mono/two_view_refinement.h"

#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <ceres/sphere_manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <glog/logging.h>

#include <cmath>
#include <memory>

#include "backend/ba/ba_loss.h"
#include "backend/ba/ba_types.h"
#include "backend/ba/pose_block.h"
#include "backend/ba/reprojection_factors.h"

namespace dala {

TwoViewRefinementSummary RefineTwoView(const PinholeCamera& camera,
                                       const std::vector<Eigen::Vector2d>& uv_ref,
                                       const std::vector<Eigen::Vector2d>& uv_cur,
                                       double sigma_px, int max_iterations, Pose* T_cur_ref,
                                       std::vector<std::optional<Eigen::Vector3d>>* p_ref) {
  CHECK_EQ(uv_ref.size(), uv_cur.size());
  CHECK_EQ(uv_ref.size(), p_ref->size());
  CHECK_LT(std::abs(T_cur_ref->translation().norm() - 1.0), 1e-6) << "the baseline must be 1";
  StereoIntrinsics K;
  K.fx = camera.fx;
  K.fy = camera.fy;
  K.cx = camera.cx;
  K.cy = camera.cy;
  K.baseline = 0.0;

  PoseBlock x_ref = PoseToBlock(Pose::Identity());
  PoseBlock x_cur = PoseToBlock(T_cur_ref->inverse());  // T_w_cur, |t_w_cur| = 1.
  std::vector<Eigen::Vector3d> points;
  std::vector<size_t> index;
  for (size_t i = 0; i < p_ref->size(); ++i) {
    if (!(*p_ref)[i]) continue;
    points.push_back(*(*p_ref)[i]);
    index.push_back(i);
  }
  TwoViewRefinementSummary summary;
  summary.num_points = static_cast<int>(points.size());
  if (points.empty()) return summary;

  ceres::Problem problem;  // Takes ownership of costs, manifolds and the loss.
  ceres::LossFunction* loss = MakeLoss(RobustLoss::kHuber, std::sqrt(kChi2Quantile95Dof2)).release();
  problem.AddParameterBlock(x_ref.data(), 7);
  problem.SetParameterBlockConstant(x_ref.data());
  problem.AddParameterBlock(
      x_cur.data(), 7,
      new ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::SphereManifold<3>>());
  const auto observation = [&](const Eigen::Vector2d& uv) {
    BaObservation o;
    o.uv = uv;
    o.sigma_px = sigma_px;
    return o;
  };
  for (size_t k = 0; k < points.size(); ++k) {
    problem.AddResidualBlock(CreateReprojectionCost(K, observation(uv_ref[index[k]])), loss,
                             x_ref.data(), points[k].data());
    problem.AddResidualBlock(CreateReprojectionCost(K, observation(uv_cur[index[k]])), loss,
                             x_cur.data(), points[k].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_SCHUR;
  options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  options.max_num_iterations = max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(options, &problem, &ceres_summary);
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.usable = ceres_summary.IsSolutionUsable();
  if (!summary.usable) return summary;

  *T_cur_ref = BlockToPose(x_cur).inverse();
  for (size_t k = 0; k < points.size(); ++k) {
    double depth_ref = 0.0, depth_cur = 0.0;
    const double e_ref =
        WhitenedSquaredError(K, observation(uv_ref[index[k]]), x_ref.data(), points[k].data(),
                             &depth_ref);
    const double e_cur =
        WhitenedSquaredError(K, observation(uv_cur[index[k]]), x_cur.data(), points[k].data(),
                             &depth_cur);
    if (depth_ref <= 0 || depth_cur <= 0 || e_ref > kChi2Quantile95Dof2 ||
        e_cur > kChi2Quantile95Dof2) {
      (*p_ref)[index[k]].reset();
      ++summary.num_dropped;
    } else {
      (*p_ref)[index[k]] = points[k];
    }
  }
  return summary;
}

}  // namespace dala
