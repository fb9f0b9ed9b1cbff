#ifndef DALA_BACKEND_BA_POSE_GRAPH_PROBLEM_H_
#define DALA_BACKEND_BA_POSE_GRAPH_PROBLEM_H_

// What the SE(3) and the Sim(3) pose graphs share (backend/ba/pose_graph.h,
// backend/ba/sim3_pose_graph.h): one parameter block per keyframe on `manifold`, the first one
// (smallest id) held constant (the gauge), one residual per edge whitened by the upper Cholesky
// factor U of its information (U^T U = information), then SolvePoseGraphProblem. Internal to
// backend/ba.

#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <array>
#include <cstddef>
#include <type_traits>
#include <map>
#include <vector>

#include "backend/ba/ba_loss.h"
#include "backend/ba/pose_graph.h"

namespace dala {

// `make_cost(edge, sqrt_info)` returns the edge's ceres::CostFunction (blocks: from, to).
// Returns summary.usable; the blocks hold the solution when it is.
template <size_t kBlockSize, typename Edge, typename MakeCost>
bool SolvePoseGraph(std::map<KeyframeId, std::array<double, kBlockSize>>* blocks,
                    ceres::Manifold* manifold, const std::vector<Edge>& edges,
                    const PoseGraphOptions& options, const MakeCost& make_cost,
                    PoseGraphSummary* summary) {
  using Information = std::decay_t<decltype(Edge().information)>;
  auto loss = MakeLoss(options.loss, options.loss_scale);
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (auto& [id, x] : *blocks)
    problem.AddParameterBlock(x.data(), static_cast<int>(kBlockSize), manifold);
  problem.SetParameterBlockConstant(blocks->begin()->second.data());
  for (const Edge& e : edges) {
    CHECK(blocks->count(e.from) && blocks->count(e.to))
        << "pose-graph edge " << e.from << " -> " << e.to << " refers to an unknown keyframe";
    Eigen::LLT<Information> llt(0.5 * (e.information + e.information.transpose()));
    CHECK(llt.info() == Eigen::Success)
        << "edge " << e.from << " -> " << e.to << ": information is not positive definite";
    const Information sqrt_info = llt.matrixU();
    problem.AddResidualBlock(make_cost(e, sqrt_info), loss.get(), blocks->at(e.from).data(),
                             blocks->at(e.to).data());
  }
  SolvePoseGraphProblem(options, &problem, summary);
  return summary->usable;
}

}  // namespace dala

#endif  // DALA_BACKEND_BA_POSE_GRAPH_PROBLEM_H_
